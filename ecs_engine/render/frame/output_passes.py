"""What the frame's primary command buffer records around the render path's secondaries, by the
target's form (gpu/scene_attachments.py's Form), every drawing a dynamic rendering in a pass of
the output graph (render/passes/output_graph.py), which places the barriers:

- `direct`: the scene's rendering into the target: the chunks', the sky's (sky_pass.py), the
  set-aside rows' and the light billboards' (light_pass.py) secondaries; then the overlay (the
  editor's ImGui) in a rendering of its own that loads the target (its one pipeline, made for the
  target's format, serves every form: no pipeline follows a change of form), and the readback
  (render/passes/readback.py) where asked;
- `hdr`: the scene's rendering into the HDR colour as above (with MSAA resolved at its end),
  then the barrier that leaves the HDR colour (and single-sample depth) in
  SHADER_READ_ONLY_OPTIMAL; then the post effects (`post`); then the output graph
  (render/passes/output_graph.py: the tone map sampling the HDR colour, the ldr effects, the
  overlay, the readback, every barrier of the target image up to its final layout);
- `deferred`: the G-buffer rendering with the chunks' secondaries (gpu/gbuffer.py), the ray
  shadows where traced, the lighting compute pass (lighting/deferred.py), weighted
  transparency's accumulation where on (passes of the output graph too:
  render/passes/deferred_passes.py), then as `hdr` with the sky, the set-aside rows and the
  billboards alone in the scene's rendering.

Post effects go in `OutputPasses.post`: callables `post(cb, inputs)` (inputs: the frame's
post/inputs.py PostInputs: the target's single-sample HDR colour, a gpu/memory.py Image with
`handle`, `view`, `format`, `width`, `height`, sampled and, where the device can, storage usage;
the scene's single-sample depth (None with MSAA); the extent; the camera's projection), called in
order after the scene's rendering and before the tone map, in the hdr and deferred forms only
(the direct form has no HDR colour). Each finds the images in SHADER_READ_ONLY_OPTIMAL, the
scene's writes visible to fragment and compute shaders, and must leave them so, its own writes
made visible to the tone map's fragment-shader reads (its own barriers, until the renderer's frame
graph places them). The renderer sets them from its post effects of the "hdr" stage
(post/registry.py; `set_post`) and hands the frame's camera to `begin_post` before the frame's
replay key is taken (the effects' keys read the inputs: SSAO's projection).

Post effects of the "ldr" stage (FXAA) run on the tone-mapped image in the output graph: with any
on, the tone map writes an intermediate image (a transient), the effects write the target and the
overlay draws over it.

With `mark` (gpu/frames.py's FrameRing.mark, while passes are timed) each pass's end is marked
with its name (the output graph's passes by theirs); a rendering whose contents are secondaries
cannot hold a timestamp, so the scene's (billboards included) is marked once, at its end.

It also keeps, per output image and form, the structs a frame needs (path.TargetState, and the
output image's final barrier); pipelines are made per AttachmentFormats, so a change of
form remakes nothing and waits for nothing.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from functools import partial
from typing import Any

from ...gpu.device import Device
from ...gpu.secondary import SecondaryBuffers
from ..config import Form, Transparency
from ..draw.path import TargetState
from ..lighting.deferred import DeferredPass
from ..passes.light_billboards import LightPass
from ..passes.oit import WeightedTransparency
from ..passes.output_graph import OutputGraph
from ..passes.sky import SkyPass
from ..passes.tone_map import ToneMapPass
from ..post.inputs import PostInputs
from .scene_renderings import scene_state

log = logging.getLogger("ecs_engine")

#: a post effect: called with the primary command buffer and the frame's PostInputs (see the module)
PostPass = Callable[[Any, PostInputs], None]


class OutputRendering:
    """One target image: its handle and view, which the output graph imports."""

    def __init__(self, target: Any, output: Any) -> None:
        self.image, self.view = target.output_image(output)


class OutputPasses:
    def __init__(
        self,
        device: Device,
        target: Any,
        frame_set_layout: Any,
        secondaries: SecondaryBuffers,
        light_size: float,
        clear_color: tuple[float, float, float],
    ) -> None:
        self.device = device
        self.vk = device.vk
        self.target = target
        self.secondaries = secondaries
        self.clear_color = clear_color
        self.light_pass = LightPass(device, frame_set_layout, secondaries, light_size)
        self.tone_map_pass: ToneMapPass | None = None
        self.deferred: DeferredPass | None = None
        self.sky: SkyPass | None = None
        self.oit: WeightedTransparency | None = None  # made the first frame it is asked for
        self._warned_blend = False
        self.ray_shadows: Any = None  # render/raytracing/shadows.py's RayShadows where shadows are traced
        self.post: list[PostPass] = []  # the post effects, in order (see the module)
        self.graph: OutputGraph | None = None  # the hdr and deferred forms' output (set_post makes it)
        self.scene: Any = None  # the renderer's ScenePasses (scene_passes.py): ahead of forward
        self.inputs: PostInputs | None = None  # the frame's, for the hdr stage (begin_post)
        try:
            self.tone_map_pass = ToneMapPass(device, target.color_format)
            self.deferred = DeferredPass(device, frame_set_layout)
            self.sky = SkyPass(device, frame_set_layout, secondaries)
        except BaseException:
            self.destroy()
            raise
        # per (output, form, width, height): the frame's structs (see target_state)
        self._targets: dict[tuple[Any, str, int, int], tuple[TargetState, OutputRendering, Any]] = {}
        # target_state's last answer: its key, state, output rendering, the scene's formats
        self._last: tuple[Any, TargetState | None, OutputRendering | None, Any] = (None,) * 4
        self._recreations = getattr(target, "recreations", 0)  # the swapchain's, when _targets were made

    def target_state(self, framebuffer: Any, width: int, height: int) -> TargetState:
        """What drawing into the target's output `framebuffer` (one of its images: output_image)
        at this size in its current form needs per frame, made once (kept for 16 of them)."""
        target = self.target
        key = (framebuffer, target.form, width, height)
        recreations = getattr(target, "recreations", 0)
        if recreations != self._recreations:  # new swapchain images and attachments, maybe at the same size
            self._targets.clear()
            self._last = (None,) * 4
            self._recreations = recreations
        last = self._last
        if last[0] == key and last[1] is not None:
            return last[1]  # the same output and form as the last frame's (offscreen: every frame)
        made = self._targets.get(key)
        if made is None:
            if len(self._targets) > 16:  # swapchains come and go: drop the old outputs' entries
                self._targets.clear()
            vk = self.vk
            state, formats = scene_state(vk, target, framebuffer, width, height, self.clear_color, self.secondaries)
            rendering = OutputRendering(target, framebuffer)
            made = self._targets[key] = (state, rendering, formats)
        self._last = (key, *made)
        return made[0]

    @property
    def formats(self) -> Any:
        """The scene's rendering's AttachmentFormats for the last target_state's form."""
        return self._last[3]

    def _rendering(self, state: TargetState) -> OutputRendering:
        """The output rendering made with `state` (target_state's answer for this frame)."""
        if self._last[1] is state and self._last[2] is not None:
            return self._last[2]
        for made, rendering, _ in self._targets.values():
            if made is state and rendering is not None:
                return rendering
        raise ValueError("a target state this output did not make")

    def weighted(self, mode: str) -> WeightedTransparency | None:
        """The weighted transparency pass ready for the target, when `mode` asks for it and the
        target is in the deferred form (it needs the opaque depth before the target's pass)."""
        target = self.target
        if mode != Transparency.WEIGHTED or target.form != Form.DEFERRED:
            return None
        if not self.device.features.get("independentBlend"):
            if not self._warned_blend:
                log.warning("%s lacks independentBlend: blended rows are sorted instead", self.device.info.name)
                self._warned_blend = True
            return None
        if self.oit is None:
            self.oit = WeightedTransparency(self.device, self.secondaries)
        state = self._last[1]  # this frame's: a camera view's size (render/frame/views.py), else the target's
        width, height = (state.key[1], state.key[2]) if state is not None else (target.width, target.height)
        self.oit.ensure(target.attachments.images[0], width, height)
        return self.oit

    def forget_path_state(self) -> None:
        """Drop what the old render path kept per target (its recorder's frame states)."""
        for state, _, _ in self._targets.values():
            state.path_state.clear()

    def forget_pipelines(self) -> None:
        """Pipelines made again from the shader files on next use (hot reload; the caller waited
        for the device): the billboards', sky's, composite's and tone map's."""
        assert self.tone_map_pass is not None and self.sky is not None
        self.light_pass.forget_pipelines()
        self.sky.forget_pipelines()
        if self.oit is not None:
            self.oit.forget_composites()
        self.tone_map_pass.destroy()
        self.tone_map_pass = ToneMapPass(self.device, self.target.color_format)

    def record(
        self,
        cb: Any,
        chunks: list[Any],
        aside: Any,
        billboards: int,
        state: TargetState,
        frame_set: Any,
        tone_map: tuple[str, float],
        features: int,
        overlay: Any = None,
        slot: int = 0,
        sky: bool = False,
        transparent: Any = None,
        mark: Callable[[str], None] | None = None,
        readback: bool = False,
    ) -> int:
        """Raw cffi calls with structs made once (see gpu/frames.py for why). `chunks`: the path's
        secondaries; `aside`: the set-aside rows' or None; `billboards` point and spot lights get
        one; `features`: the mesh pipelines' MATERIAL_FEATURES (the lighting's too); `sky`: the
        Environment is drawn behind; `transparent`: the blended rows' secondary for the weighted
        transparency pass (the deferred form); `mark`: see the module; `readback`: the target
        copied to the host (the target's take_readback says for which image). Returns the light
        pass's draws."""
        target = self.target
        secondaries = chunks
        if self.graph is None:
            self.graph = OutputGraph(self, [])
        frame = self.graph.frame
        if target.form == Form.DEFERRED:  # the chunks in the G-buffer pass, lit before the scene's rendering
            assert self.deferred is not None
            frame.chunks, frame.frame_set, frame.features = chunks, frame_set[0], features
            ray = self.ray_shadows
            self.deferred.traced = ray is not None  # the lighting's mask full size only if traced into
            if ray is not None and ray.lights:  # the shadow mask the lighting reads (raytracing/shadows.py)
                frame.ray = ray
            frame.transparent = transparent
            secondaries = []
        formats = self.formats  # the scene rendering's, in this frame's form (target_state)
        if sky:  # after the opaque chunks, before the blended rows
            assert self.sky is not None
            secondaries = [*secondaries, self.sky.record(state, frame_set, slot, formats)]
        if aside is not None:
            secondaries = [*secondaries, aside]  # after every chunk's rows
        if transparent is not None:  # the weighted transparency over all of it
            assert self.oit is not None
            secondaries = [*secondaries, partial(self._composite, formats, state, slot)]  # forward records it
        lights, draws = self.light_pass.record(slot, state, formats, frame_set, billboards)
        if lights is not None:  # last, depth-tested against everything, blended over it
            secondaries = [*secondaries, lights]
        rendering = self._rendering(state)
        self.graph.record(cb, state, rendering, secondaries, tone_map, overlay, slot, mark, readback)
        return draws

    def _composite(self, formats: Any, state: TargetState, slot: int, ctx: Any) -> Any:
        """Weighted transparency's composite secondary, its set naming the graph's targets
        (called by the forward pass, once the graph is compiled: render/passes/forward.py)."""
        assert self.oit is not None
        self.oit.name_targets((ctx.image("oit_accum"), ctx.image("oit_reveal")))
        return self.oit.record_composite(formats, state, slot)

    def begin_post(self, camera: Any) -> PostInputs | None:
        """The hdr stage's inputs for this frame (`camera`: the frame's CameraMatrices), kept
        for `record`; None without an hdr-stage effect or HDR colour. Called before the frame's
        replay key is taken (the effects' keys read it)."""
        target = self.target
        hdr = target.hdr_image if self.post and target.hdr else None  # (post first: the usual frame has none)
        if hdr is None:  # no hdr-stage effect (or no HDR colour): nothing to hand over
            self.inputs = None
            return None
        depth = target.depth_image
        self.inputs = PostInputs(hdr, depth, (int(hdr.width), int(hdr.height)), camera.projection)
        return self.inputs

    def set_post(self, hdr: list[Any], ldr: list[Any]) -> None:
        """The post effects from the next frame: `hdr` called as `post` (see the module), `ldr`
        (effect objects with `add`, post/registry.py) in the output graph. The effects are the
        caller's (destroy() destroys those set last); the graph is made again when the ldr
        effects change (the caller waited for the device)."""
        self.post = list(hdr)
        if self.graph is not None and self.graph.effects == list(ldr):
            return
        if self.graph is not None:
            self.graph.destroy()
        self.graph = OutputGraph(self, ldr)

    def destroy(self) -> None:
        if self.graph is not None:
            for effect in self.graph.effects:
                effect.destroy()
            self.graph.destroy()
        for post in self.post:
            if hasattr(post, "destroy"):
                post.destroy()
        self.light_pass.destroy()
        if self.sky is not None:
            self.sky.destroy()
        if self.oit is not None:
            self.oit.destroy()
        if self.tone_map_pass is not None:
            self.tone_map_pass.destroy()
        if self.deferred is not None:
            self.deferred.destroy()
