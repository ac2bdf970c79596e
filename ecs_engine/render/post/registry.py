"""The post effects a renderer can run, by name: each effect's module registers itself here
(`register(PostEffectKind(...))` at its end), and `BUILT_IN` lists the engine's effect modules,
imported the first time the names are asked for. The render configuration's rule for `post`
(config.py), the CLI's `--post`, the editor's toggles, the App's plugins and the renderer
(`Renderer.set_post_effects`) all read this table: a new effect is its own module and shader
plus one line in `BUILT_IN`.

A kind says:
- `stage`: "hdr" (on the scene's HDR colour, before the tone map: bloom) or "ldr" (on the
  tone-mapped image, before the UI: FXAA);
- `settings`: its settings class (a frozen dataclass; `settings()` gives the defaults);
- `make(device, settings)`: the effect object for a renderer on `device`. An hdr one adds its
  passes to the output's frame graph with `effect.add_hdr(graph, extent)`, between the scene's
  rendering and the tone map: they read and write the graph's "hdr" (the single-sample HDR colour,
  rgba16f, sampled and storage: written in place) and may read its "depth" (the scene's depth
  format, sampled); the graph places the barriers (bloom_effect.py, ssao_effect.py; an object
  without `add_hdr` is called `effect(cb, inputs)` outside the graph instead, and places its own).
  An ldr one adds its passes with `effect.add(graph, source, target, create)` (the image names, and
  the description of `target` when it is an intermediate the effect's pass must create). Both have
  `key(inputs)` (what a recorded frame depends on, given this frame's post/inputs.py PostInputs:
  frame replay), `destroy()`, and optionally `begin_frame(inputs)` (each frame's PostInputs before
  the keys are asked: the camera's projection, the extent). A game's effect names its own SPIR-V by
  path (gpu/pipeline.py `shader_path`); `fullscreen_pipeline` (post/fxaa.py) makes a full-screen
  pass's pipeline;
- `depth`: it reads the scene's single-sample depth (config.py refuses it with MSAA);
- `before`: effects of its stage it runs ahead of (SSAO's composite darkens the HDR colour
  before bloom spreads it); otherwise a stage runs in registration order.

This module imports nothing of the renderer or of Vulkan; the effects' modules do.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any, Final

from ...errors import UsageError

STAGES: Final = ("hdr", "ldr")  # in the order a frame runs them

# the engine's effects, one module each (it registers itself when imported)
BUILT_IN: Final[tuple[str, ...]] = (
    "ecs_engine.render.post.ssao_effect",
    "ecs_engine.render.post.bloom_effect",
    "ecs_engine.render.post.fxaa_effect",
)


@dataclass(frozen=True)
class PostEffectKind:
    name: str  # what the config, the CLI (--post NAME) and the editor call it
    stage: str  # "hdr" or "ldr" (see the module)
    settings: type  # its settings class; settings() gives the defaults
    make: Callable[[Any, Any], Any]  # (device, settings) -> the effect object
    description: str = ""  # one line: the CLI's help, the editor's tooltip
    depth: bool = False  # reads PostInputs.depth (single-sample: refused with MSAA)
    before: tuple[str, ...] = ()  # effects of its stage it runs ahead of

    def __post_init__(self) -> None:
        if self.stage not in STAGES:
            raise UsageError(f"post effect {self.name!r}: stage must be one of {', '.join(STAGES)}, got {self.stage!r}")
        if not self.name or not self.name.replace("_", "").isalnum() or self.name != self.name.lower():
            raise UsageError(f"post effect name {self.name!r}: lower-case letters, digits and _")

    def check_settings(self, settings: Any) -> Any:
        """`settings`, or the defaults for None; a UsageError for another class's value."""
        if settings is None:
            return self.settings()
        if not isinstance(settings, self.settings):
            raise UsageError(f"{self.name} settings must be {self.settings.__name__}, got {settings!r:.80}")
        return settings


_KINDS: dict[str, PostEffectKind] = {}
_loaded = False


def register(kind: PostEffectKind) -> PostEffectKind:
    """Add the effect `kind`; returns it. A name taken by another module's effect is a
    UsageError; the same module registering it again (a reloaded module) replaces it."""
    taken = _KINDS.get(kind.name)
    if taken is not None and _module(taken) != _module(kind):
        raise UsageError(
            f"post effect {kind.name!r} is taken (by {_module(taken)}); unregister it first or choose another name"
        )
    _KINDS[kind.name] = kind
    return kind


def _module(kind: PostEffectKind) -> str:
    return getattr(kind.make, "__module__", None) or "?"


def unregister(name: str) -> PostEffectKind:
    """Remove the effect `name` (a test's or a game's own, when it is done with it); returns its
    kind. Renderers with it on keep their effect objects until they turn it off. An unknown
    name: UsageError."""
    _load()  # a built-in one loaded later would come back
    found = _KINDS.pop(name, None)
    if found is None:
        raise UsageError(f"unknown post effect {name!r}; choices: {', '.join(sorted(_KINDS)) or 'none'}")
    return found


def _load() -> None:
    global _loaded
    if not _loaded:
        for module in BUILT_IN:
            importlib.import_module(module)
        _loaded = True


def kinds() -> dict[str, PostEffectKind]:
    """Every registered effect by name, in registration order."""
    _load()
    return dict(_KINDS)


def names() -> frozenset[str]:
    return frozenset(kinds())


def kind(name: str) -> PostEffectKind:
    found = kinds().get(name)
    if found is None:
        raise UsageError(f"unknown post effect {name!r}; choices: {', '.join(sorted(kinds())) or 'none'}")
    return found


def ordered(wanted: Iterable[str]) -> tuple[str, ...]:
    """`wanted` in the order a frame runs them: the hdr stage's, then the ldr stage's, each in
    registration order but for a kind's `before` (moved ahead of the first of those in its
    stage; one pass: enough while no two kinds' `before` conflict); UsageError naming an
    unknown one."""
    wanted = set(wanted)
    for name in sorted(wanted):
        kind(name)
    every = kinds()
    found: list[str] = []
    for stage in STAGES:
        names = [n for n, k in every.items() if k.stage == stage and n in wanted]
        for name in list(names):  # each moved ahead of the first effect it must precede
            ahead = [names.index(b) for b in every[name].before if b in names]
            if ahead and min(ahead) < names.index(name):
                names.remove(name)
                names.insert(min(ahead), name)
        found += names
    return tuple(found)


def depth_readers(names: Iterable[str]) -> tuple[str, ...]:
    """Those of `names` (registered ones) that read the scene's depth, sorted."""
    every = kinds()
    return tuple(sorted(n for n in names if n in every and every[n].depth))
