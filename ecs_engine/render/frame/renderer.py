"""The renderer: one frame from `FrameData` to a submitted command buffer.

Data goes one way: the extract stage reads the world (frame_data.py, extract/), the renderer
writes the frame's mapped buffers (globals, lights, instance rows) and records; it never writes
the world. The mesh rows are drawn by a render path picked by name from PATHS (path.py, switched
by path_settings.py); the chunks of rows are jobs on the worker pool, each recording a secondary
(in `indirect` only writing rows for the compute shaders). The primary records the passes around
them by the target's form (output_passes.py; target_forms.py picks the form between frames)."""

from __future__ import annotations

import threading
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
from ..draw.path import FrameStats, PathContext, RenderPath, TargetState
from ..extract.frame_data import FrameData, FrameExtractor
from ..extract.materials import extract_materials
from ..layouts import (
    BINDING_TEXTURES,
    FEATURE_CLUSTERED,
)
from ..lighting.clusters import LightCulling
from ..lighting.environment import EnvironmentMap
from ..passes.set_aside import SetAsidePass
from ..raytracing.shadows import RayShadows
from ..shadows.maps_pass import ShadowPass
from .draw_frame import FrameDrawing, FrameRequest
from .output_passes import OutputPasses
from .path_settings import MODES, PATHS, RECORDER_NAMES, PathSettings  # noqa: F401 (importers name MODES here)
from .replay import FrameReplay
from .resources import FrameResources, frame_sets
from .scene_passes import ScenePasses
from .target_forms import TargetForms
from .viewport import EditorViewport
from .views import Views, several_views


class Renderer(FrameDrawing, PathSettings, TargetForms, CullingSetting):
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
        self.viewport: EditorViewport | None = None  # the editor's Scene window: the scene drawn there (viewport.py)
        self.extractor = FrameExtractor(lambda: self.jobs.threads if self.jobs is not None else 1, chunk_rows)
        self.views = Views(self.extractor.threads)  # several cameras' views (views.py); nothing made yet
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
        alone (self.materials, self.extract); everything after it reads the frame's snapshot.
        Cameras with a Viewport draw each into its rectangle of the window (views.py). With the
        editor's `viewport` sized, the scene is drawn into its image and the UI into the window
        (viewport.py)."""
        request = FrameRequest(world, readback, framebuffer, extent, wait, signal, dt)
        viewport = self.viewport
        if viewport is not None and self.overlay is not None and viewport.area(self.target) is not None:
            return viewport.draw(self, request)
        return self.draw_scene(request)

    def draw_scene(self, request: FrameRequest) -> FrameStats:
        """`render`'s `request` into the target as it stands (the viewport's while it draws)."""
        world = request.world
        if self.views.on or several_views(world):
            drawn = self.views.draw(self, request)
            if drawn is not None:
                return drawn
        materials = self.materials(world)
        self._blends = materials.blends
        if request.framebuffer is None:
            self.ensure_output()  # the target's own image: its form can change here
        width, height = request.extent or (self.target.width, self.target.height)
        data = self.extract(world, width, height, materials, request.dt)  # before any GPU state: a bad world fails here
        wait, signal = request.wait, request.signal
        return self._draw(data, materials, width, height, request.framebuffer, request.readback, wait, signal)

    def destroy(self) -> None:
        self.device.wait_idle()
        self.path.destroy()
        self._destroy_shared()

    def _destroy_shared(self) -> None:
        """What the renderer made, in reverse (what a failed __init__ had not made yet is skipped)."""
        if self._set_aside is not None:
            self._set_aside.destroy()
        names = "views scene output per_frame shadows environment texture_pages lights ray_shadows pool set_layout"
        for name in ["viewport", *names.split(), "secondaries", "frames"]:
            made = getattr(self, name, None)
            for part in made if isinstance(made, list) else [made] if made is not None else []:
                part.destroy()
