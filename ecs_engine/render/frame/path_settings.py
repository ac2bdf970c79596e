"""Which render path draws and what its pipelines are specialised for: the mode and recorder, the
fill, the material features and the settings as one RenderConfig, each changed between frames by
making the path again (the old one stays if the new cannot be made). A part of Renderer (its
base class), apart for its size; `_make_path` is the renderer's, which knows the target."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ... import native
from ...errors import UsageError
from ..config import Caps, RenderConfig, Shadows, check
from ..draw.chunk_paths import RECORDERS, InstancedPath, PerEntityPath, check_recorder
from ..draw.indirect_path import IndirectPath
from ..draw.path import PathFactory, RenderPath

__all__ = ["MODES", "PATHS", "RECORDER_NAMES", "PathSettings"]

PATHS: dict[str, PathFactory] = {
    "instanced": InstancedPath,
    "per_entity": PerEntityPath,
    "indirect": IndirectPath,
}
MODES = tuple(PATHS)
RECORDER_NAMES = tuple(RECORDERS)


class PathSettings:
    """Renderer's path methods; the attributes they use are the renderer's."""

    device: Any
    path: RenderPath
    cpu_recorder: str
    fill: str
    material_features: int
    target: Any
    lod: bool
    output: Any
    shadows: Any
    _set_aside: Any
    _native: Any
    _anisotropy: Any
    _make_path: Callable[[str, str], RenderPath]
    shadow_method: Shadows  # TargetForms'
    post_effects: Any  # post/effects.py's

    @property
    def mode(self) -> str:
        return self.path.name

    @property
    def recorder(self) -> str:
        """The path's: native or python, or gpu when the GPU writes the draws (indirect)."""
        return self.path.recorder

    @property
    def config(self) -> RenderConfig:
        """The settings in force, as one value (config.py); changed through the setters."""
        same = ("mode", "culling", "light_culling", "shadow_denoise", "transparency", "tone_map", "exposure", "fill")
        kept = {"recorder": self.cpu_recorder, "shadows": self.shadow_method, "msaa": self.target.samples}
        kept.update(lod=self.lod, anisotropy=self._anisotropy, post=self.post_effects)
        return RenderConfig.from_strings(**{n: getattr(self, n) for n in same}, **kept)

    def set_path(self, mode: str, recorder: str | None = None) -> None:
        """Draw with another path (or recorder) from the next frame; nothing else is rebuilt.
        The recorder is kept for the CPU paths while the indirect one draws."""
        recorder = recorder or self.cpu_recorder
        if mode == self.mode and recorder == self.cpu_recorder:
            return
        if mode not in PATHS:
            raise ValueError(f"unknown render mode {mode!r}; modes: {', '.join(MODES)}")
        if mode == self.mode and not self.path.uses_recorder:
            check_recorder(recorder)  # kept for when a CPU path draws again
            self.cpu_recorder = recorder
            return
        self._swap_path(self._make_path(mode, recorder))  # raises before the old one goes

    def _swap_path(self, new: RenderPath) -> None:
        self.device.wait_idle()  # frames in flight may still use the old path's pipelines
        self.path.destroy()
        if self._set_aside is not None:  # its pipelines were made for the old path's context
            self._set_aside.destroy()
            self._set_aside = None
        self.output.forget_path_state()
        self.shadows.forget_path()  # made again for the new path's context
        self.path = new

    def _native_recorder(self) -> Any:
        """The native recorder compiled for this device, made on first use (about a second)."""
        if self._native is None:
            if not native.AVAILABLE:
                raise UsageError(
                    "the native recorder needs numba (pip install numba, and unset "
                    "ECS_ENGINE_NO_NUMBA); or use --recorder python"
                )
            from ...gpu.native_recorder import NativeRecorder

            self._native = NativeRecorder(self.device)
        return self._native

    def check_fill(self, fill: str) -> None:
        """Raise (UsageError) unless this device can draw meshes with `fill` (config.RULES)."""
        check(RenderConfig.from_strings(fill=fill), Caps.of(self.device), only=("fill",))

    def set_fill(self, fill: str) -> None:
        """Rasterise meshes as `fill` from the next frame (the path's pipelines are rebuilt)."""
        self.check_fill(fill)
        if fill != self.fill:
            old = self.fill
            self.fill = fill
            self._respecialise(lambda: setattr(self, "fill", old))

    def _check_features(self, features: int) -> None:
        """Rebuild the path's pipelines when the world's materials or lights need a shading model,
        alpha mask or light kind they were specialised without (grown, never shrunk)."""
        wanted = self.material_features | features
        if wanted != self.material_features:
            old = self.material_features
            self.material_features = wanted
            self._respecialise(lambda: setattr(self, "material_features", old))

    def _respecialise(self, undo: Callable[[], None]) -> None:
        """The current path again, its pipelines made for the settings just changed (fill,
        material features, clustered lights); `undo` puts the old setting back if they cannot be
        made, and the old path stays."""
        try:
            self._swap_path(self._make_path(self.mode, self.cpu_recorder))
        except BaseException:
            undo()
            raise
