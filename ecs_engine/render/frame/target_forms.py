"""How the renderer's target is drawn (gpu/scene_attachments.py's forms): forward into the target
("direct"), through HDR colour ("hdr") or through a G-buffer lit in compute ("deferred"), as the
light culling, tone map, exposure, MSAA, blended materials and ray-traced shadows need; switched
between frames without waiting for the device (the target keeps each form's attachments, the
pipelines are made per attachment formats: render/draw/path_pipelines.py); the shadow method too
(ray-traced shadows need the deferred form). A part of Renderer (its base class), apart for its
size."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..config import Form, Shadows, Transparency
from ..extract.frame_data import FrameData
from ..layouts import FEATURE_RAY_SHADOWS
from ..lighting.clusters import ClusterGrid, check_light_culling
from ..passes.tone_map import wants_hdr
from ..post.effects import PostEffects
from ..raytracing.shadows import RayShadows, check_shadow_method


class TargetForms(PostEffects):
    """Renderer's target-form methods; the attributes they use are the renderer's. The post
    effects' methods (post/effects.py) come with them: they need the hdr form."""

    device: Any
    target: Any
    lights: Any
    transparency: str
    tone_map: str
    exposure: float
    output: Any
    overlay: Any
    ray_shadows: Any
    cpu_recorder: str
    meshes: Any
    frames: Any
    set_layout: Any
    material_features: int
    _shadow_denoise: bool
    _blends: bool
    _swap_path: Callable[[Any], None]
    _make_path: Callable[[str, str], Any]
    _respecialise: Callable[[Callable[[], None]], None]

    @property
    def mode(self) -> str:  # the renderer's path's
        raise NotImplementedError

    @property
    def light_culling(self) -> str:
        return self.lights.mode

    @light_culling.setter
    def light_culling(self, mode: str) -> None:
        check_light_culling(mode)
        self.lights.mode = mode

    @property
    def clustered(self) -> bool:
        return self.lights.clustered

    @property
    def shadow_method(self) -> Shadows:
        """maps, or raytraced (ray_shadows.py)."""
        return Shadows.RAYTRACED if self.ray_shadows is not None else Shadows.MAPS

    @property
    def shadow_denoise(self) -> bool:
        """Ray-traced soft shadows are filtered (shadow_denoise.py); kept while maps are drawn."""
        return self._shadow_denoise

    @shadow_denoise.setter
    def shadow_denoise(self, on: bool) -> None:
        self._shadow_denoise = bool(on)
        if self.ray_shadows is not None:
            self.ray_shadows.denoise = self._shadow_denoise

    def set_shadow_method(self, method: str) -> None:
        """Shadow maps or ray-traced shadows from the next frame (a device without ray tracing
        refuses raytraced: UsageError, nothing changed)."""
        check_shadow_method(method, self.device, self.target.samples)
        if method == self.shadow_method:
            return
        self.device.wait_idle()
        frames, layout = len(self.frames.frames), self.set_layout.handle
        made = RayShadows(self.device, self.meshes, frames, layout) if method == Shadows.RAYTRACED else None
        if self.ray_shadows is not None:
            self.ray_shadows.destroy()
        self.ray_shadows = self.output.ray_shadows = made
        self.shadow_denoise = self._shadow_denoise
        if made is None and self.material_features & FEATURE_RAY_SHADOWS:  # the maps' lookups again
            self.material_features &= ~FEATURE_RAY_SHADOWS
            self._swap_path(self._make_path(self.mode, self.cpu_recorder))
        self.ensure_output()  # the deferred form for the rays, or the form the rest needs

    def _light_clusters(self, data: FrameData, width: int, height: int, own_target: bool) -> ClusterGrid | None:
        """This frame's cluster grid, or None for the all-lights loop; a change either way
        rebuilds the mesh pipelines (FEATURE_CLUSTERED), undone if that fails. With `auto` it
        also changes the form (deferred or not): on the target's own image at once; a
        swapchain's frame stays in the form its output state was asked in and the next one
        switches (ensure_output, from the run loop)."""
        grid, flipped = self.lights.plan(data, width, height, self.target.samples)
        if flipped:

            def undo() -> None:
                self.lights.clustered = not self.lights.clustered

            if own_target and self._wanted_form() != self.target.form:
                try:
                    self.ensure_output()
                except BaseException:
                    undo()
                    raise
            else:
                self._respecialise(undo)
        return grid

    def ensure_output(self) -> None:
        """Give the target the form the tone map, exposure and blended materials need (HDR colour
        or straight into the target). Call between frames (the run loop calls it before each)."""
        self._fit_target()

    def _wanted_form(self) -> Form:
        """The target form (gpu/scene_attachments.py) the light culling, tone map, exposure, MSAA,
        blended materials and post effects need."""
        samples = self.target.samples
        if self.ray_shadows is not None:
            return Form.DEFERRED  # the G-buffer pass is the rays' depth pre-pass (render/raytracing/shadows.py)
        weighted = self.transparency == Transparency.WEIGHTED
        if self.lights.deferred(samples) or (weighted and self._blends and samples == 1):
            return Form.DEFERRED
        post = bool(self.post_effects)
        views = getattr(self, "views", None)  # (made in Renderer.__init__ before the first form)
        if views is not None and views.split:
            return Form.HDR  # several camera views draw through the HDR colour (view_graph.py)
        return Form.HDR if wants_hdr(self.tone_map, self.exposure, samples, self._blends, post) else Form.DIRECT

    def _fit_target(self) -> None:
        form = self._wanted_form()
        if form != self.target.form:  # its attachments made the first time; nothing waits
            self.target.set_form(form)

    def rebuild_pipelines(self) -> None:
        """Pipelines made again from the shader files (hot reload): the path's (the old stays if
        they cannot be made), the output passes', the post effects' and the UI's. The effects
        are made anew (they keep their pipelines), and the camera views' copies and graphs of
        them follow the new ones (render/frame/views.py remakes them when the window's change)."""
        self.device.wait_idle()  # frames in flight may use the old pipelines
        self._swap_path(self._make_path(self.mode, self.cpu_recorder))
        self.output.forget_pipelines()
        self._post_apply(self.post_effects, self.post_effects)
        if self.overlay is not None:
            self.overlay.rebuild(self.target)
