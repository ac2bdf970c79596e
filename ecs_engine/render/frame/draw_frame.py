"""One frame's recording and submission from its snapshot (`FrameData`): a part of Renderer (its
base class), apart for its size. `Renderer.render` draws the window's one camera through it once
a frame; several camera views (views.py) draw through it once per view, each its own frame slot,
extent and output graph."""

from __future__ import annotations

import time
from dataclasses import replace
from functools import partial
from typing import Any, NamedTuple

from ..assets.materials import Materials
from ..config import Form, Mode
from ..draw.path import FrameInputs, FrameStats
from ..extract.frame_data import FrameData
from ..layouts import FEATURE_DEFORM, FEATURE_ENVIRONMENT, FEATURE_RAY_SHADOWS, FEATURE_SHADOWS, INSTANCE
from ..lighting.rows import light_features, write_light_shadows
from ..passes.set_aside import SetAsidePass
from ..shadows.maps_pass import ShadowPass
from .jobs import run_jobs
from .replay import frame_key


class FrameRequest(NamedTuple):
    """What one `Renderer.render` call asks (its arguments, made once there): the `world` to draw,
    `readback` of the target, the output image (`framebuffer`; None: the target's own) at
    `extent` (None: the target's size), the swapchain's semaphores to `wait` for and `signal`,
    and `dt` (seconds since the last frame, for temporal culling). Handed down unchanged through
    the editor's viewport (viewport.py, which names its own image and size) and the camera views
    (views.py). A named tuple: made every frame, and a tuple is made in C."""

    world: Any
    readback: bool = False
    framebuffer: Any = None
    extent: tuple[int, int] | None = None
    wait: Any = None
    signal: Any = None
    dt: float | None = None


class FrameDrawing:
    """Renderer's frame methods; the attributes they use are the renderer's."""

    device: Any
    target: Any
    jobs: Any
    frames: Any
    per_frame: list[Any]
    shadows: Any
    environment: Any
    ray_shadows: Any
    texture_pages: Any
    output: Any
    scene: Any
    path: Any
    meshes: Any
    secondaries: Any
    replay: Any
    views: Any
    overlay: Any
    ambient: Any
    tone_map: str
    exposure: float
    lod: bool
    mode: Mode
    transparency: str
    material_features: int
    _set_aside: SetAsidePass | None
    _gbuffer_formats: Any
    _jobs_generation: int
    _check_features: Any
    _light_clusters: Any
    _sync_textures: Any
    _forget_old_threads: Any
    target_state: Any
    _make_shadow_path: Any

    def _draw(
        self,
        data: FrameData,
        materials: Materials,
        width: int,
        height: int,
        framebuffer: Any,
        readback: bool,
        wait: Any,
        signal: Any,
    ) -> FrameStats:
        """Record and submit the frame of `data` at `width` x `height` (see Renderer.render)."""
        material_count = len(materials)
        # lights with a Shadow: the views their maps are drawn from, or their rays (and maps
        # too for the rows lit forward, which the rays' per-pixel mask does not cover, and for
        # the lights past the traced ones)
        ray = self.ray_shadows
        traced = ray.plan(data) if ray is not None else []
        forward = data.set_aside is not None and len(data.set_aside) > 0
        only = None if ray is None or forward else ray.overflow
        views = self.shadows.plan(data, only) if only is None or only else []
        if self.environment.sync(data.environment, self.jobs):  # a new Environment (the device was waited for)
            for each in self.per_frame:
                each.name_environment(self.device)
        features = light_features(data.lights, data.directional) | (FEATURE_SHADOWS if views else 0)
        features |= FEATURE_SHADOWS | FEATURE_RAY_SHADOWS if traced else 0
        features |= FEATURE_ENVIRONMENT if self.environment.active else 0
        features |= FEATURE_DEFORM if data.deform is not None else 0
        self._check_features(materials.features | features)
        grid = self._light_clusters(data, width, height, own_target=framebuffer is None)
        self._sync_textures(materials)
        if self.jobs is not None and self.jobs.generation != self._jobs_generation:
            self._forget_old_threads()
        frame, gpu_ms = self.frames.acquire()  # its primary is opened only when it must be recorded
        self.views.recordings.take(self, frame)  # a camera view's own recording in the slot (view_frames.py)
        slot = frame.slot
        pf = self.per_frame[slot]
        if self.shadows.ensure(views):  # new maps (the device was waited for): every set names them
            for each in self.per_frame:
                each.name_shadow_maps(self.device, self.shadows.maps)
        camera_rows = self.path.rows_needed(data.candidates) + len(data.set_aside or ())
        rows = camera_rows + (len(views) * ShadowPass.view_rows(data, self.path) if views else 0)  # each view's after
        pf.ensure_capacity(self.device, self.texture_pages, rows, data.light_count, material_count, len(views))
        if data.deform is not None:  # skinned or morphed rows: their joints and weights, the meshes' data named
            levels = self.lod and self.mode == Mode.INDIRECT  # the indirect mode draws their levels of detail
            pf.write_deform(self.device, data.deform, self.meshes.skin_buffer(levels))
        deferred = self.target.form == Form.DEFERRED
        named = self.shadows.light_views(views) if views else {}
        places = ray.places(traced) if ray is not None and traced else {}
        name = None  # a frame without shadows names nothing (and pays nothing for it)
        if named or places:
            eye = data.camera.position - data.origin
            name = partial(write_light_shadows, data.lights, data.directional, eye, data.origin, named, places=places)
        positional = pf.write_frame(self.device, data, materials, grid, self.ambient, deferred, name)
        if ray is not None and traced:
            ray.prepare(slot, data, self.jobs, width, height, materials)
        target = self.target_state(self.target.framebuffer if framebuffer is None else framebuffer, width, height)
        self.path.draw_into(self._gbuffer_formats if deferred else self.output.formats, deferred)  # the chunks'
        self.output.begin_post(data.camera)  # the post effects' frame inputs: their keys (below) read them
        # None: the frame records; else the output graph's passes' keys and the prelude's (replay.py)
        self.scene.begin_slot(self.path, slot, pf, grid, data.light_count, views)
        key = frame_key(self, target, slot, (positional, grid, data.light_count, readback), (views, traced, forward))
        reuse = self.replay.offer(slot, key)
        inputs = FrameInputs(
            slot=slot,
            descriptor_set=pf.descriptor_set,
            set_array=pf.set_array,
            target=target,
            planes=data.planes,
            instances=pf.instances.array(INSTANCE.dtype),
            bounds=self.meshes.bounds(),
            readback=readback,
            material_count=material_count,
            data=data,
            lod=self.lod,
            reuse=reuse,
        )
        path = self.path
        path.begin_frame(inputs)
        if reuse is None:  # else the slot's secondaries stay recorded, for the chunks to give back
            self.secondaries.reset(slot)
        if self.overlay is not None:
            self.overlay.prepare(slot, len(self.frames.frames))
        t0 = time.perf_counter()

        self.shadows.prepare(views, inputs, pf, camera_rows, data, path, self._make_shadow_path)
        aside_casters = data.set_aside.casters if data.set_aside is not None else []
        results, shadow_buffers = run_jobs(self.jobs, path, inputs, self.shadows, data.chunks, aside_casters)
        record_ms = (time.perf_counter() - t0) * 1e3
        again = self.replay.replay(slot, results) if reuse is not None else None
        if again is not None:  # every chunk as the slot last recorded it: its primary as it stands
            light_draws, aside = again.light_draws, (None, 0, 0, 0, None)
            self.frames.resubmit(frame, wait=wait, signal=signal)
        else:
            self.frames.open(frame)
            cb = frame.command_buffer
            mark = self.frames.marker(frame)  # None unless passes are timed (gpu/frames.py)
            secondaries = path.finish(cb, inputs, results, data.candidates)  # its compute: the graph's "cull"
            aside = self._record_set_aside(inputs, data, materials)
            self.scene.begin(path, slot, pf, grid, data.light_count, views, shadow_buffers)  # ahead of forward
            light_draws = self.output.record(
                cb,
                secondaries,
                aside[0],
                positional,
                target,
                pf.set_array,
                (self.tone_map, self.exposure),
                self.material_features,
                self.overlay,
                slot,
                sky=self.environment.sky,
                transparent=aside[4],
                mark=mark,
                readback=readback,  # the output graph's last pass
            )
            self.frames.end(frame, wait=wait, signal=signal)
            if reuse is None:
                self.replay.keep(slot, key, results, light_draws)
        if readback:
            self.frames.wait(frame)
        draws, visible, triangles = path.counts(inputs, results)
        draws, visible, triangles = draws + aside[1], visible + aside[2], triangles + aside[3]
        shadows = self.shadows
        return FrameStats(
            draws=draws + light_draws + (shadows.draws if views else 0),
            instances=visible,
            triangles=triangles + (shadows.triangles if views else 0),
            lights=data.light_count,
            gpu_ms=gpu_ms,
            wait_ms=self.frames.last_wait_ms,
            record_ms=record_ms,
            chunks=len(data.chunks),
            candidates=data.all_rows,
            replayed=again is not None,
        )

    def _record_set_aside(
        self, inputs: FrameInputs, data: FrameData, materials: Materials
    ) -> tuple[Any, int, int, int, Any]:
        """The set-aside rows' secondary, draws, rows, triangles, weighted transparency's secondary."""
        if data.set_aside is None or not len(data.set_aside):
            return None, 0, 0, 0, None
        formats = self.output.formats  # forward, in the scene's rendering (deferred: over the lit scene)
        if self._set_aside is None:
            self._set_aside = SetAsidePass(replace(self.path.ctx, formats=formats, gbuffer=False))
        elif self._set_aside.ctx.formats != formats:  # another form: its pipelines are per formats
            self._set_aside.ctx = replace(self._set_aside.ctx, formats=formats, gbuffer=False)
        first = self.path.rows_needed(data.candidates)
        eye, oit = data.camera.position - data.origin, self.output.weighted(self.transparency)
        return self._set_aside.record(inputs, data.set_aside, first, eye, materials, oit)
