"""FXAA as the post effect "fxaa" (registry.py) of the ldr stage: the output passes' frame graph
(render/frame/output_passes.py) has the tone map write an intermediate image, and this effect's pass
(fxaa.py's FxaaPass) reads it and writes the next image, the target last; the UI then draws
over the target. The pass is made again with each graph (the graph destroys it)."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ..graph import ImageDesc
from .fxaa import FxaaSettings, add_fxaa
from .registry import PostEffectKind, register


class FxaaEffect:
    def __init__(self, device: Any, settings: FxaaSettings | None = None) -> None:
        self.device = device
        self.settings = FxaaSettings() if settings is None else settings

    def add(self, graph: Any, source: str, target: str, create: ImageDesc | None = None) -> None:
        """FXAA from the image `source` into `target` (made by the pass when `create` says how)."""
        add_fxaa(graph, self.settings, source, target, create=create)

    def key(self, inputs: Any = None) -> Hashable:
        return ("fxaa", self.settings)  # the tone-mapped image alone: no frame input

    def destroy(self) -> None:
        pass  # its pass is the graph's


register(
    PostEffectKind(
        "fxaa",
        "ldr",
        FxaaSettings,
        FxaaEffect,
        "fast approximate anti-aliasing (FXAA 3.11) of the tone-mapped image, before the UI",
    )
)
