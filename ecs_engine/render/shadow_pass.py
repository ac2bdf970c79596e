"""Shadow maps drawn through the job system (issue 15), before the frame's other passes.

Each frame: the views of the lights with a `Shadow` (shadow_views.py); the map array grown to
hold them (gpu/shadow_maps.py); per view a set 0 of its own whose globals are the light's
matrices (so the render path's shaders draw from the light unchanged) and a slice of the
frame's instance buffer after the camera's rows; then every (view, chunk) pair is a job on the
worker pool: it culls the chunk against the view's planes, writes the rows and records a
secondary command buffer with a depth-only pipeline, as the camera's chunks are recorded
(chunk_paths.py: the same paths, made for the shadow render pass). The primary then draws each
view's layer: begin, execute its secondaries, end.

The lighting reads SHADOW_VIEW rows (per view its matrix, bias, normal offset, cascade split,
filter) and the map (shading.glsl's light_shadow); a light row names its first view and count.
A scene without a Shadow pays for none of it: no views, no jobs, a 1-texel map bound, and the
shaders specialised without shadows (FEATURE_SHADOWS).

A point light's six cube faces are layers of the same array, each widened by a few texels
(shadow_views.py's CUBE_MARGIN); the lighting picks the face and filters within it.

Alpha-masked materials cut their holes in the maps (chunk_paths.py's shadow_pipelines).

Not yet: the indirect mode's GPU cull per view (it draws its shadows with the instanced path's
CPU culling).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..components import Shadow
from ..ecs.world import World
from ..gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_buffers
from ..gpu.device import Device
from ..gpu.memory import Buffer
from ..gpu.secondary import SecondaryBuffers
from ..gpu.shadow_maps import ShadowMaps, create_shadow_pass
from .frame_data import NOT_CASTER, Chunk, FrameData
from .layouts import BINDING_GLOBALS, GLOBALS, SHADOW_VIEW
from .light_rows import write_light_shadows
from .path import FrameInputs, PathContext, RenderPath, TargetState
from .shadow_views import ShadowView, shadow_views

PROJECTIONS = {"cascade": 0, "spot": 1, "cube": 2}  # SHADOW_VIEW.info.w: orthographic, perspective, a cube face


class ShadowPass:
    def __init__(
        self, device: Device, frame_set_layout: DescriptorSetLayout, secondaries: SecondaryBuffers, frames: int
    ):
        self.device = device
        self.vk = device.vk
        self.set_layout = frame_set_layout
        self.secondaries = secondaries
        self.frames = frames
        self.render_pass = create_shadow_pass(device)
        self.maps: ShadowMaps | None = None
        self.pool: DescriptorPool | None = None
        try:
            self.maps = ShadowMaps(device, self.render_pass, 1, 1)  # bound until a light casts
        except BaseException:
            self.destroy()
            raise
        self.cleared = False  # the layers' layout made by a first (clearing) pass
        self._view_sets: list[list[tuple[Buffer, Any, Any]]] = [[] for _ in range(frames)]  # (globals, set, array)
        self._targets: dict[int, TargetState] = {}
        self._pool_sets = 0  # view sets the pool holds per frame slot
        self.path: RenderPath | None = None
        self.draws = self.triangles = 0  # the last frame's shadow draws

    # -------------------------------------------------------------- planning
    def plan(self, world: World, data: FrameData) -> list[ShadowView]:
        """This frame's drawn views (none without a Shadow: one query, no work)."""
        if not any(len(batch) for batch in world.query(Shadow, write=())):
            return []
        return shadow_views(world, data.camera, data.origin)

    def ensure(self, views: list[ShadowView]) -> bool:
        """Maps that hold `views` (made anew, larger, when they do not: the caller's frames in
        flight are waited for); True when the maps changed."""
        assert self.maps is not None
        if not views:
            return False
        resolution = max(v.resolution for v in views)
        if resolution == self.maps.resolution and len(views) <= self.maps.layers:
            return False
        self.device.wait_idle()
        new = ShadowMaps(self.device, self.render_pass, resolution, max(len(views), self.maps.layers))
        self.maps.destroy()
        self.maps = new
        self.cleared = False
        self._targets.clear()
        return True

    def path_for(self, ctx: PathContext, make: Any) -> RenderPath:
        """The depth-only render path (made on first use, for the renderer's current path
        context: `make(ctx)` builds a path of the right kind)."""
        if self.path is None:
            shadow_ctx = replace(ctx, render_pass=self.render_pass, gbuffer=False, shadow=True, samples=1, fill="solid")
            self.path = make(shadow_ctx)
        return self.path

    def forget_path(self) -> None:
        """The renderer's path changed (mode, recorder, features): made again when next needed."""
        if self.path is not None:
            self.path.destroy()
            self.path = None
        for state in self._targets.values():
            state.path_state.clear()

    # ------------------------------------------------------------- per frame
    def target_state(self, layer: int) -> TargetState:
        assert self.maps is not None
        state = self._targets.get(layer)
        if state is None:
            fb, res = self.maps.framebuffers[layer], self.maps.resolution
            state = self._targets[layer] = TargetState.make(
                self.vk,
                (int(self.vk.ffi.cast("uintptr_t", fb)), res, res),
                fb,
                self.render_pass,
                self.secondaries.begin_info(self.render_pass, 0, fb),
                (0.0, 0.0, 0.0),
                depth_only=True,
            )
        return state

    def view_inputs(self, views: list[ShadowView], frame: FrameInputs, row_base: int, rows: int) -> list[FrameInputs]:
        """Per view: its set 0 (globals: the light's matrices; the rest the frame's) and
        the FrameInputs its chunk jobs read; view k's rows start at row_base + k * rows."""
        sets = self._view_sets[frame.slot]
        vk = self.vk
        while len(sets) < len(views):
            if self.pool is None or len(sets) >= self._pool_sets:
                self._grow_pool(len(views))
                sets = self._view_sets[frame.slot]
                continue
            assert self.pool is not None
            descriptor_set = self.pool.allocate(self.set_layout)
            sets.append(
                (
                    Buffer(self.device, GLOBALS.size, vk.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT),
                    descriptor_set,
                    vk.ffi.new("VkDescriptorSet[1]", [descriptor_set]),
                )
            )
        out = []
        uniform = vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
        for k, view in enumerate(views):
            globals_buffer, descriptor_set, array = sets[k]
            g = globals_buffer.array(GLOBALS.dtype, 1)
            g[...] = 0
            g["projection"] = view.projection.T
            g["view"] = view.view.T
            # the frame's set copied whole (a driver may read every binding a shader declares,
            # used or not: lavapipe crashed on the unwritten ones), then the view's globals
            copies = [
                vk.VkCopyDescriptorSet(
                    srcSet=frame.descriptor_set, srcBinding=b, dstSet=descriptor_set, dstBinding=b, descriptorCount=n
                )
                for b, _, _, n in self.set_layout.bindings
                if b != BINDING_GLOBALS
            ]
            vk.vkUpdateDescriptorSets(self.device.handle, 0, None, len(copies), copies)
            write_buffers(self.device, descriptor_set, [(BINDING_GLOBALS, uniform, globals_buffer)])
            out.append(
                replace(
                    frame,
                    descriptor_set=descriptor_set,
                    set_array=array,
                    target=self.target_state(view.layer),
                    planes=view.planes,
                    readback=False,
                    row_base=row_base + k * rows,
                    path_state=None,
                )
            )
        return out

    def _grow_pool(self, views: int) -> None:
        """A pool for `views` sets per frame slot (the old sets go: the device is waited for)."""
        self.device.wait_idle()
        self._release_sets()
        per_slot = max(8, views)
        count = per_slot * self.frames
        sizes: dict[int, int] = {}
        for _, kind, _, n in self.set_layout.bindings:
            sizes[kind] = sizes.get(kind, 0) + count * n
        self.pool = DescriptorPool(self.device, count, sizes)
        self._pool_sets = per_slot

    def record_jobs(
        self, path: RenderPath, inputs: list[FrameInputs], chunks: list[Chunk], jobs: Any
    ) -> list[list[Any]]:
        """Every (view, chunk) pair a job (chunks tagged NotShadowCaster left out); per view the
        secondaries to execute, and (draws, triangles) summed."""
        casters = [c for c in chunks if not c.flags & NOT_CASTER]
        pairs = [(k, c) for k in range(len(inputs)) for c in casters]
        for view in inputs:
            path.begin_frame(view)

        def job(pair: tuple[int, Chunk]) -> Any:
            return path.record_chunk(pair[1], inputs[pair[0]])

        results = (
            jobs.map(job, pairs, lambda p: f"shadow view {p[0]}: {p[1].name}")
            if jobs is not None
            else [job(p) for p in pairs]
        )
        per_view: list[list[Any]] = [[] for _ in inputs]
        self.draws = self.triangles = 0
        for (k, _), r in zip(pairs, results, strict=True):
            if r.command_buffer is not None:
                per_view[k].append(r.command_buffer)
            self.draws += r.draws
            self.triangles += r.triangles
        return per_view

    def draw_views(
        self,
        views: list[ShadowView],
        frame: FrameInputs,
        pf: Any,
        row_base: int,
        data: FrameData,
        ctx: PathContext,
        make: Any,
        jobs: Any,
    ) -> list[list[Any]]:
        """The frame's shadow work on the CPU: the views' rows for the lighting, their sets and
        inputs, and the chunk jobs; per view the secondaries record() executes."""
        if not views:
            self.draws = self.triangles = 0
            return []
        self.write_views(pf.shadow_views.array(SHADOW_VIEW.dtype, len(views)), views)
        inputs = self.view_inputs(views, frame, row_base, data.candidates)
        return self.record_jobs(self.path_for(ctx, make), inputs, data.chunks, jobs)

    def name_lights(self, data: FrameData, views: list[ShadowView], rows: np.ndarray) -> None:
        """Each shadow-casting light's row names its first view and count (light_rows.py)."""
        first: dict[int, tuple[int, int]] = {}
        for v in views:
            start, count = first.get(v.entity, (v.layer, 0))
            first[v.entity] = (start, count + 1)
        write_light_shadows(data.lights, data.directional, data.camera.position - data.origin, data.origin, first, rows)

    def write_views(self, out: np.ndarray, views: list[ShadowView]) -> None:
        """SHADOW_VIEW rows of the views (shading.glsl's light_shadow reads them)."""
        for k, v in enumerate(views):
            perspective = v.kind != "cascade"
            p = v.projection.astype(np.float64)
            row = out[k]
            row["view_projection"] = (p @ v.view.astype(np.float64)).T
            if perspective:  # depth = P22 + P23 / d: a world bias b at distance d is P23 * b / d^2
                bias, offset = p[2, 3] * v.bias * v.texel, v.normal_offset * v.texel
            else:  # depth = P22 * z + P23: linear
                bias, offset = p[2, 2] * v.bias * v.texel, v.normal_offset * v.texel
            row["params"] = (bias, offset, v.far if np.isfinite(v.far) else 3.0e38, v.softness)
            row["info"] = (v.layer, v.filter, v.resolution, PROJECTIONS[v.kind])
            row["depth_model"] = (p[2, 2], p[2, 3], v.texel, 0.0)

    def record(self, cb: Any, views: list[ShadowView], secondaries: list[list[Any]]) -> None:
        """Each view's layer drawn from its secondaries (raw calls); the first time the maps are
        used, every layer is cleared, so none is read in an undefined layout."""
        assert self.maps is not None
        vk = self.vk
        lib = vk.lib
        drawn = {v.layer: s for v, s in zip(views, secondaries, strict=True)}
        layers = range(self.maps.layers) if not self.cleared else drawn.keys()
        for layer in layers:
            state = self.target_state(layer)
            lib.vkCmdBeginRenderPass(cb, state.pass_begin_ptr, vk.VK_SUBPASS_CONTENTS_SECONDARY_COMMAND_BUFFERS)
            buffers = drawn.get(layer)
            if buffers:
                lib.vkCmdExecuteCommands(cb, len(buffers), vk.ffi.new("VkCommandBuffer[]", buffers))
            lib.vkCmdEndRenderPass(cb)
        self.cleared = True

    def _release_sets(self) -> None:
        for sets in self._view_sets:
            for buffer, _, _ in sets:
                buffer.destroy()
        self._view_sets = [[] for _ in range(self.frames)]
        if self.pool is not None:
            self.pool.destroy()
            self.pool = None

    def destroy(self) -> None:
        if self.path is not None:
            self.path.destroy()
            self.path = None
        self._release_sets()
        if self.maps is not None:
            self.maps.destroy()
            self.maps = None
        self.vk.vkDestroyRenderPass(self.device.handle, self.render_pass, None)
