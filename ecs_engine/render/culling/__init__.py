"""Culling methods as one interface: `CullingMethod` (method.py says what each stage
asks it) and its four implementations, picked from config.Culling by `culling_method`, the one
factory. Before it, culling was decided under three encodings: names compared in the extractor
and the renderer, a boolean `occlusion` in FrameInputs, and `planes is None` / `masks is None`
standing for "no culling" / "not temporal"; now planes and masks are only the data a method
produced, and each stage asks the method.

```python
method = culling_method("temporal")         # or a Culling, or True / False (frustum / none)
method.supports("indirect")                 # False: config.RULES says why (method.refusal)
```
"""

from __future__ import annotations

from typing import Any

from ..config import Culling, RenderConfig, check
from .method import CullingMethod, FrustumCulling, NoCulling
from .occlusion import OcclusionCulling
from .temporal import TemporalCulling

__all__ = [
    "METHODS",
    "CullingMethod",
    "CullingSetting",
    "FrustumCulling",
    "NoCulling",
    "OcclusionCulling",
    "TemporalCulling",
    "check_culling",
    "culling_method",
    "culling_name",
]

METHODS: dict[Culling, type[CullingMethod]] = {
    m.name: m for m in (FrustumCulling, TemporalCulling, OcclusionCulling, NoCulling)
}


def culling_name(culling: str | bool | Culling | CullingMethod) -> Culling:
    """The Culling named (True: frustum, False: none; a method: its own); UsageError naming the
    choices for an unknown one."""
    if isinstance(culling, CullingMethod):
        return culling.name
    if isinstance(culling, bool):
        return Culling.FRUSTUM if culling else Culling.NONE
    found: Culling = Culling.parse(culling, "culling")
    return found


def culling_method(culling: str | bool | Culling) -> CullingMethod:
    """A new method for the culling named (culling_name's names)."""
    return METHODS[culling_name(culling)]()


def check_culling(culling: str | bool | Culling, mode: str | None = "instanced") -> str:
    """The culling method's name (culling_name); UsageError for an unknown one, or (unless
    `mode` is None) one that `mode` cannot cull with (config.RULES: temporal is the CPU modes',
    occlusion the indirect mode's)."""
    name = culling_name(culling)
    if mode is not None:
        check(RenderConfig.from_strings(culling=name, mode=mode), only=("culling",))
    return str(name.value)


class CullingSetting:
    """The culling of what draws (the Renderer's base): `culling_method`, and `culling`, its
    name, which callers read and set (another name: a new method from the next frame; the same
    one keeps the method, and temporal culling's state)."""

    culling_method: CullingMethod

    @property
    def culling(self) -> str:
        return str(self.culling_method.name.value)

    @culling.setter
    def culling(self, value: Any) -> None:
        name = culling_name(value)
        if getattr(self, "culling_method", None) is None or name is not self.culling_method.name:
            self.culling_method = METHODS[name]()
