"""The renderer: one frame from `FrameData` to a submitted command buffer.

Data goes one way: the extract stage reads the world (frame_data.py, extract/), the renderer
writes the frame's mapped buffers (globals, lights, instance rows) and records; it never writes
the world. The mesh rows are drawn by a render path picked by name from PATHS (path.py, switched
by path_settings.py); the chunks of rows are jobs on the worker pool, each recording a secondary
(in `indirect` only writing rows for the compute shaders). The primary records the passes around
them by the target's form (output_passes.py; target_forms.py picks the form between frames)."""

from __future__ import annotations

import threading
import time
from dataclasses import replace
from functools import partial
from typing import Any

from ...ecs.world import World
from ...gpu.descriptors import write_images
from ...gpu.device import Device
from ...gpu.frames import FrameRing
from ...gpu.gbuffer import gbuffer_formats
from ...gpu.secondary import SecondaryBuffers
from ...jobs import JobPool
from ..assets.materials import Materials
from ..assets.mesh_registry import MeshRegistry
from ..assets.texture_pages import TexturePages
from ..config import Caps, Form, Mode, RenderConfig, Shadows, check
from ..culling import CullingSetting
from ..draw.chunk_paths import InstancedPath, PerEntityPath, check_recorder, default_recorder
from ..draw.path import FrameInputs, FrameStats, PathContext, RenderPath, TargetState
from ..extract.frame_data import FrameData, FrameExtractor
from ..extract.materials import extract_materials
from ..layouts import (
    BINDING_TEXTURES,
    FEATURE_CLUSTERED,
    FEATURE_ENVIRONMENT,
    FEATURE_RAY_SHADOWS,
    FEATURE_SHADOWS,
    INSTANCE,
)
from ..lighting.clusters import LightCulling
from ..lighting.environment import EnvironmentMap
from ..lighting.rows import light_features, write_light_shadows
from ..passes.set_aside import SetAsidePass
from ..raytracing.shadows import RayShadows
from ..shadows.maps_pass import ShadowPass
from .jobs import FrameJobs, job_name
from .output_passes import OutputPasses
from .path_settings import MODES, PATHS, RECORDER_NAMES, PathSettings  # noqa: F401 (importers name MODES here)
from .replay import FrameReplay, frame_key
from .resources import FrameResources, frame_sets
from .scene_passes import ScenePasses
from .target_forms import TargetForms


class Renderer(PathSettings, TargetForms, CullingSetting):
    def __init__(
        self,
        device: Device,
        target: Any,
        meshes: MeshRegistry,
        *,
        mode: str = "instanced",
        recorder: str | None = None,
        jobs: JobPool | None = None,
        culling: str | bool = "frustum",
        chunk_rows: int | None = None,
        native_recorder: Any = None,
        clear_color: tuple[float, float, float] = (0.02, 0.02, 0.03),
        ambient: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 0.06),
        light_size: float = 0.08,
        fill: str = "solid",
        tone_map: str = "clamp",
        exposure: float = 0.0,
        light_culling: str = "auto",
        transparency: str = "sorted",
        lod: bool = True,
        shadows: str = "maps",
        shadow_denoise: bool = True,
        anisotropy: int | None = None,  # textures' (1: off; None: the device's best, up to 16)
        post: Any = (),  # post effects: names, or name -> settings (post/effects.py, set_post_effects)
    ) -> None:
        self.vk, self.device = device.vk, device
        # every setting against the one table (config.RULES), before anything is made: a refusal
        # leaves nothing to destroy, and names every setting this device refuses at once
        asked = dict(mode=mode, recorder=recorder, culling=culling, fill=fill, tone_map=tone_map, exposure=exposure)
        asked.update(light_culling=light_culling, transparency=transparency, lod=lod, shadows=shadows)
        asked.update(shadow_denoise=shadow_denoise, anisotropy=anisotropy, msaa=target.samples)
        check(RenderConfig.from_strings(**asked), Caps.of(device))
        self._anisotropy = anisotropy  # as asked (None: the device's best), for `config`
        # blended rows: sorted, or weighted (oit_pass.py: deferred form); levels of detail (indirect mode)
        self.transparency, self.lod = transparency, lod
        self.tone_map, self.exposure = tone_map, float(exposure)  # change them between frames (ensure_output)
        self.target = target
        self._blends = False  # the last frame's world had blended materials (they need HDR colour)
        self.meshes, self.clear_color, self.ambient = meshes, clear_color, ambient
        self.jobs = jobs
        self._jobs_generation = jobs.generation if jobs is not None else 0
        self.culling = culling  # its method (culling_method; True: frustum; False: none): CullingSetting
        self.region: tuple[float, float, float, float] | None = None  # the view's part of the target (camera.py)
        self.extractor = FrameExtractor(lambda: self.jobs.threads if self.jobs is not None else 1, chunk_rows)
        self._native = native_recorder  # compiling one costs about a second: callers may share one
        self.cpu_recorder = recorder or default_recorder()  # the CPU paths' recorder, kept while indirect draws
        self._set_aside: SetAsidePass | None = None  # blended materials, made on first use
        # drawn last, after the tone map: an object with prepare(slot, frames_in_flight),
        # record(cb, slot, width, height) and rebuild(target), e.g. imgui_pass.ImGuiRenderer
        self.overlay: Any = None
        # what the mesh pipelines were specialised for (Materials.features): grown, never shrunk,
        # when a world's materials use another shading model (a pipeline rebuild, as a mode switch)
        self.default_materials = Materials()  # a world without a Materials resource: the default palette
        self.material_features = self.default_materials.features
        self.fill = fill
        self.ray_shadows: RayShadows | None = None  # shadows="raytraced" (ray_shadows.py): the deferred form
        self._shadow_denoise = bool(shadow_denoise)  # its soft shadows filtered (shadow_denoise.py)
        self._post_init(post)  # checked, and the target's first form follows them
        try:
            self.frames = FrameRing(device)
            n = len(self.frames.frames)
            self.replay = FrameReplay(n)  # frames submitted again while their recording would repeat
            self.secondaries = SecondaryBuffers(device, n)
            self.set_layout, self.pool = frame_sets(device, n)
            traced = shadows == Shadows.RAYTRACED
            self.ray_shadows = RayShadows(device, meshes, n, self.set_layout.handle) if traced else None
            self.shadow_denoise = shadow_denoise
            self.lights = LightCulling(device, self.set_layout.handle, light_culling)
            self._fit_target()  # its first form's attachments: the path's formats follow it
            self._gbuffer_formats = gbuffer_formats(device.vk)
            self.texture_pages = TexturePages(device, anisotropy)
            self.shadows = ShadowPass(device, self.set_layout, self.secondaries, n)
            self.environment = EnvironmentMap(device)
            self.per_frame = [
                FrameResources.make(
                    device, self.pool, self.set_layout, self.texture_pages, self.shadows.maps, self.environment
                )
                for _ in range(n)
            ]
            self.output = OutputPasses(
                device, target, self.set_layout.handle, self.secondaries, light_size, clear_color
            )
            self.output.ray_shadows = self.ray_shadows
            self.output.scene = self.scene = ScenePasses(device, self.lights, self.shadows)
            self._post_make()
            self.path: RenderPath = self._make_path(mode, recorder or default_recorder())
        except BaseException:
            # a form or path the device cannot make (indirect), no numba, no memory: nothing leaks
            self._destroy_shared()
            raise

    # ------------------------------------------------------------------ paths
    @property
    def chunk_rows(self) -> int | None:
        return self.extractor.chunk_rows

    def _make_shadow_path(self, ctx: PathContext) -> RenderPath:
        """The depth-only path of the shadow passes' CPU jobs: the per-entity one for per_entity,
        else the instanced one (indirect: the set-aside casters alone; shadow_indirect.py culls)."""
        return (PerEntityPath if self.mode == Mode.PER_ENTITY else InstancedPath)(ctx, self.cpu_recorder)

    def _make_path(self, mode: str, recorder: str) -> RenderPath:
        check_recorder(recorder)
        deferred = self.target.form == Form.DEFERRED
        ctx = PathContext(
            device=self.device,
            meshes=self.meshes,
            formats=gbuffer_formats(self.vk) if deferred else self.target.formats(self.vk),
            frame_set_layout=self.set_layout.handle,
            secondaries=self.secondaries,
            frames_in_flight=len(self.frames.frames),
            material_features=self.material_features | (FEATURE_CLUSTERED if self.lights.walked_by_fragments else 0),
            samples=self.target.samples,
            fill=self.fill,
            native_recorder=self._native_recorder,
            gbuffer=deferred,
        )
        path = PATHS[mode](ctx, recorder)
        self.cpu_recorder = recorder
        return path

    # ----------------------------------------------------------------- set-up
    def _sync_textures(self, materials: Materials) -> None:
        """Upload textures the materials' registry added; then every frame's set names the new
        pages (the upload waited for the GPU, so no frame in flight reads the old ones)."""
        if self.texture_pages.sync(materials.textures):
            infos = self.texture_pages.image_infos()
            for pf in self.per_frame:
                write_images(self.device, pf.descriptor_set, BINDING_TEXTURES, infos)
                pf.set_version += 1  # the shadow views' copies of the set name the old pages

    def target_state(self, framebuffer: Any, width: int, height: int) -> TargetState:
        """What drawing into output image `framebuffer` at this size needs per frame, made once (output_passes.py)."""
        return self.output.target_state(framebuffer, width, height)

    def next_image_semaphore(self) -> Any:
        """The semaphore the next frame waits on for a swapchain image, once that frame slot's
        last use is done (so the semaphore is free to be signalled again)."""
        frame = self.frames.frames[self.frames.index]
        self.frames.wait(frame)
        return frame.image_available

    def _forget_old_threads(self) -> None:
        """The pool's threads were replaced: the old threads' command pools go (after the GPU is
        done with what they recorded)."""
        assert self.jobs is not None
        self.device.wait_idle()
        self.secondaries.keep_threads({t.ident for t in threading.enumerate() if t.ident is not None})
        self._jobs_generation = self.jobs.generation

    # -------------------------------------------------------------- per frame
    def materials(self, world: World) -> Materials:
        """The world's materials, or the default palette (the extract stage's: extract/materials.py)."""
        return extract_materials(world, self.default_materials)

    def extract(
        self, world: World, width: int, height: int, materials: Materials | None = None, dt: float | None = None
    ) -> FrameData:
        materials = self.materials(world) if materials is None else materials
        args = (self.culling_method, len(materials), materials.set_aside(), self.region, dt, self.meshes.bounds())
        return self.extractor.extract(world, width / height, len(self.meshes), *args, materials=materials)

    def render(
        self,
        world: World,
        readback: bool = False,
        framebuffer: Any = None,
        extent: tuple[int, int] | None = None,
        wait: Any = None,
        signal: Any = None,
        dt: float | None = None,
    ) -> FrameStats:
        """Record and submit one frame (`dt`: seconds since the last, for temporal culling).
        Headless targets read the image back when asked. The world is read by the extract stage
        alone (self.materials, self.extract); everything after it reads the frame's snapshot."""
        materials = self.materials(world)
        self._blends = materials.blends
        if framebuffer is None:
            self.ensure_output()  # the target's own image: its form can change here
        width, height = extent or (self.target.width, self.target.height)
        material_count = len(materials)
        data = self.extract(world, width, height, materials, dt)  # before any GPU state: a bad world fails here
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
        self._check_features(materials.features | features)
        grid = self._light_clusters(data, width, height, own_target=framebuffer is None)
        self._sync_textures(materials)
        if self.jobs is not None and self.jobs.generation != self._jobs_generation:
            self._forget_old_threads()
        frame, gpu_ms = self.frames.acquire()  # its primary is opened only when it must be recorded
        slot = frame.slot
        pf = self.per_frame[slot]
        if self.shadows.ensure(views):  # new maps (the device was waited for): every set names them
            for each in self.per_frame:
                each.name_shadow_maps(self.device, self.shadows.maps)
        camera_rows = self.path.rows_needed(data.candidates) + len(data.set_aside or ())
        rows = camera_rows + len(views) * ShadowPass.view_rows(data, self.path)  # each view's after the camera's
        pf.ensure_capacity(self.device, self.texture_pages, rows, data.light_count, material_count, len(views))
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
        work = FrameJobs(path, inputs, self.shadows, data.chunks, aside_casters)  # one batch: camera and shadows
        done = self.jobs.map(work.run, work.work, job_name) if self.jobs is not None else list(map(work.run, work.work))
        results, shadow_buffers = work.results(done)
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
        return FrameStats(
            draws=draws + light_draws + self.shadows.draws,
            instances=visible,
            triangles=triangles + self.shadows.triangles,
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

    def destroy(self) -> None:
        self.device.wait_idle()
        self.path.destroy()
        self._destroy_shared()

    def _destroy_shared(self) -> None:
        """What the renderer made, in reverse (what a failed __init__ had not made yet is skipped)."""
        if self._set_aside is not None:
            self._set_aside.destroy()
        names = "scene output per_frame shadows environment texture_pages lights ray_shadows pool set_layout"
        for name in [*names.split(), "secondaries", "frames"]:
            made = getattr(self, name, None)
            for part in made if isinstance(made, list) else [made] if made is not None else []:
                part.destroy()
