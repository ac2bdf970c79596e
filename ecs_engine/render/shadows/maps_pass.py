"""Shadow maps drawn through the job system (issue 15), before the frame's other passes.

Each frame: the views of the lights with a `Shadow` (shadow_views.py); the map array grown to
hold them (gpu/shadow_maps.py); per view a set 0 of its own whose globals are the light's
matrices (so the render path's shaders draw from the light unchanged) and a slice of the
frame's instance buffer after the camera's rows. The chunk jobs (frame_jobs.py) then cull each
chunk against the camera and every view in one pass, write each view's visible rows and record
a secondary per view with a depth-only pipeline (chunk_paths.py: the same paths, made for the
maps' formats; view_recording.py: all of it in one native call). The frame graph's
"shadow_maps" pass (maps_graph.py) then draws each view's layer with dynamic rendering: per
view begin rendering over its layer's corner, execute its secondaries, end; it declares the
layers it writes and the passes that sample the maps declare their reads, so the graph places
the barriers (the layers to their attachment layout, then to the one the lighting samples).

The lighting reads SHADOW_VIEW rows (per view its matrix, bias, normal offset, cascade split,
filter) and the map (shading.glsl's light_shadow); a light row names its first view and count.
A scene without a Shadow pays for none of it: no views, no jobs, a 1-texel map bound, and the
shaders specialised without shadows (FEATURE_SHADOWS).

A point light's six cube faces are layers of the same array, each widened by a few texels
(shadow_views.py's CUBE_MARGIN); the lighting picks the face and filters within it.

Alpha-masked materials cut their holes in the maps (chunk_paths.py's shadow_pipelines).

In the indirect mode the chunks' rows are culled on the GPU per view (shadow_indirect.py): the
compute passes and a secondary per view are recorded here, before the views' renderings; the
chunk jobs only write the camera's rows, and the CPU path culls and draws the set-aside casters
(blended materials and the like) alone.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ...gpu.descriptors import DescriptorSetLayout
from ...gpu.device import Device
from ...gpu.owned import Owned
from ...gpu.secondary import SecondaryBuffers
from ...gpu.shadow_maps import ShadowMaps, shadow_formats
from ..draw.indirect_path import IndirectPath
from ..draw.instance_rows import cull_views, padded_planes
from ..draw.path import ChunkResult, FrameInputs, PathContext, RenderPath, TargetState
from ..draw.view_recording import PathHandles, ViewRecording, can_fuse
from ..extract.frame_data import Chunk, FrameData
from ..layouts import SHADOW_VIEW
from .indirect import IndirectShadows
from .view_sets import ShadowViewSets
from .views import ShadowView, light_views, shadow_views, write_view_rows


class ShadowPass:
    def __init__(
        self, device: Device, frame_set_layout: DescriptorSetLayout, secondaries: SecondaryBuffers, frames: int
    ):
        self.device = device
        self.vk = device.vk
        self.set_layout = frame_set_layout
        self.secondaries = secondaries
        self.frames = frames
        self.formats = shadow_formats(device.vk)  # what its pipelines and secondaries are made for
        self.secondary_begin = secondaries.begin_info_rendering(self.formats)
        self.maps: ShadowMaps | None = None
        self.path: RenderPath | None = None
        self.gpu: IndirectShadows | None = None  # the indirect mode's GPU-culled views
        # the view sets, the maps, the depth-only path and the GPU culling: the last three made
        # again while it lives (released from here and the new ones added)
        self.owned = Owned(device)
        try:
            self.view_sets = self.owned.add(ShadowViewSets(device, frame_set_layout, frames))
            self.maps = self.owned.add(ShadowMaps(device, 1, 1))  # bound until a light casts
        except BaseException:
            self.destroy()
            raise
        self._targets: dict[tuple[int, int], TargetState] = {}  # by (layer, texels across)
        self._counts = [0, 0]  # the last frame's shadow draws and triangles recorded on the CPU
        self._gpu_frame = False  # this frame's views are culled on the GPU
        self.last_views: list[ShadowView] = []  # the last plan's (the editor's map thumbnails)
        self._planned: tuple[Any, Any, Any] | None = None  # (casters, camera matrices, origin...) it was for
        # per slot: the (views, buffer, maps) its rows were written for
        self._views_written: list[tuple[Any, Any, Any] | None] = [None] * frames
        self._inputs: list[FrameInputs] = []  # this frame's views' (prepare)
        self._recording: Any = None  # the path this frame's jobs record with
        self._planes = padded_planes([])  # this frame's views' (V, 24) culling planes
        self._fused: ViewRecording | None = None  # the views as one native call a job
        self._path_handles: PathHandles = {}  # the fused recordings' paths' handles (view_recording.py)

    # -------------------------------------------------------------- planning
    def plan(self, data: FrameData, only: set[int] | None = None) -> list[ShadowView]:
        """This frame's drawn views (none without a Shadow: no work), of every casting light
        (the snapshot's, data.shadows) or of those whose entities are in `only`; the last
        frame's list itself while the camera, the origin and the casters are the same objects
        (the extractor keeps them while their columns are unchanged: extract/shadows.py)."""
        casters = data.shadows
        if casters is None:
            self.last_views, self._planned = [], None
            return self.last_views
        key = (data.origin_key, None if only is None else frozenset(only))
        kept = self._planned
        if kept is not None and kept[0] is casters and kept[1] is data.camera and kept[2] == key:
            return self.last_views
        self.last_views = shadow_views(casters, data.camera, data.origin, only)
        self._planned = (casters, data.camera, key)
        return self.last_views

    def ensure(self, views: list[ShadowView]) -> bool:
        """Maps that hold `views` (made anew, larger, when they do not: the caller's frames in
        flight are waited for); True when the maps changed."""
        assert self.maps is not None
        if not views:
            return False
        resolution = max([v.resolution for v in views])
        if resolution == self.maps.resolution and len(views) <= self.maps.layers:
            return False
        self.device.wait_idle()
        new = ShadowMaps(self.device, resolution, max(len(views), self.maps.layers))
        self.owned.release(self.maps)
        self.maps = self.owned.add(new)
        self._targets.clear()
        return True

    def path_for(self, ctx: PathContext, make: Any) -> RenderPath:
        """The depth-only render path (made on first use, for the renderer's current path
        context: `make(ctx)` builds a path of the right kind)."""
        if self.path is None:
            shadow_ctx = replace(ctx, formats=self.formats, gbuffer=False, shadow=True, samples=1, fill="solid")
            self.path = self.owned.add(make(shadow_ctx))
        return self.path

    def forget_path(self) -> None:
        """The renderer's path changed (mode, recorder, features): made again when next needed."""
        if self.path is not None:
            self.owned.release(self.path)
            self.path = None
        if self.gpu is not None:
            self.owned.release(self.gpu)
            self.gpu = None
        for state in self._targets.values():
            state.path_state.clear()

    # ------------------------------------------------------------- per frame
    def target_state(self, layer: int, resolution: int | None = None) -> TargetState:
        """The target of `layer`'s first `resolution` texels across (the whole layer by default):
        a view is drawn at the resolution its light asks for, in the corner of a layer as large as
        the largest any light asks (its render area, viewport and scissor; the lighting scales its
        coordinates: shadow_views.write_view_rows, and never read past the corner, whose outside is left
        undefined by each frame's pass). The H100 drew the shadows demo's 11 layers at 2048 in ~5.4 ms,
        rasterising and clearing texels that the 512-texel cube faces never read."""
        assert self.maps is not None
        res = self.maps.resolution if resolution is None else min(int(resolution), self.maps.resolution)
        state = self._targets.get((layer, res))
        if state is None:
            view = self.maps.layer_views[layer]
            state = self._targets[(layer, res)] = TargetState.make(
                self.vk,
                (int(self.vk.ffi.cast("uintptr_t", view)), res, res),
                None,  # dynamic rendering: no framebuffer or render pass (record())
                self.secondary_begin,
                (0.0, 0.0, 0.0),
                depth_only=True,
            )
        return state

    def view_inputs(
        self, views: list[ShadowView], frame: FrameInputs, set_version: int, row_base: int, rows: int
    ) -> list[FrameInputs]:
        """Per view: its set 0 (globals: the light's matrices; the rest the frame's, copied
        again only when the frame's set was written since: `set_version`) and the FrameInputs
        its chunk jobs read; view k's rows start at row_base + k * rows."""
        sets = self.view_sets.ensure(frame.slot, len(views), frame.descriptor_set, set_version)
        out = []
        for k, view in enumerate(views):
            view_set = sets[k]
            view_set.hold(view)
            out.append(
                frame.but(
                    descriptor_set=view_set.descriptor_set,
                    set_array=view_set.set_array,
                    target=self.target_state(view.layer, view.resolution),
                    planes=view.planes,
                    readback=False,
                    row_base=row_base + k * rows,
                    path_state=None,
                )
            )
        return out

    def prepare(
        self,
        views: list[ShadowView],
        frame: FrameInputs,
        pf: Any,
        row_base: int,
        data: FrameData,
        camera: RenderPath,
        make: Any,
    ) -> None:
        """The frame's shadow work before its jobs (frame_jobs.py hands them out): the views'
        rows for the lighting, their sets, inputs and culling planes; `camera` is the camera's
        path (its begin_frame done), whose jobs may cull the camera's view with the shadows'."""
        self._counts = [0, 0]
        self._fused = None
        self._gpu_frame = False
        if not views:
            self._inputs = []
            return
        written = self._views_written[frame.slot]
        now = (views, pf.shadow_views, self.maps)
        if written is None or any(a is not b for a, b in zip(written, now, strict=True)):  # not in these rows yet
            assert self.maps is not None
            write_view_rows(pf.shadow_views.array(SHADOW_VIEW.dtype, len(views)), views, self.maps.resolution)
            self._views_written[frame.slot] = now
        # the set-aside casters' rows sit after the chunks' in a view's region (their offsets): with
        # the GPU culling the chunks' rows in place, the region holds those alone
        gpu = isinstance(camera, IndirectPath)
        first = row_base - (data.candidates if gpu else 0)
        self._inputs = self.view_inputs(views, frame, pf.set_version, first, self.view_rows(data, camera))
        path = self._recording = self.path_for(camera.ctx, make)
        for view in self._inputs:
            path.begin_frame(view)
        if isinstance(camera, IndirectPath):  # the chunks' rows culled on the GPU per view
            if self.gpu is not None and self.gpu.camera is not camera:
                self.device.wait_idle()  # made for a path that is gone (forget_path was not called)
                self.owned.release(self.gpu)
                self.gpu = None
            if self.gpu is None:
                self.gpu = self.owned.add(IndirectShadows(camera, self.formats))
            self.gpu.begin_frame(frame.slot, frame.readback)
            self._gpu_frame = True
        self._planes = padded_planes([frame.planes] + [view.planes for view in self._inputs])  # the camera's first
        if can_fuse([path]):  # one native call a job (view_recording.py)
            if can_fuse([camera]):
                paths, inputs = [camera] + [path] * len(views), [frame] + self._inputs
                self._fused = ViewRecording(paths, inputs, self._planes, True, self._path_handles)
            else:
                paths = [path] * len(views)
                self._fused = ViewRecording(paths, self._inputs, self._planes[1:], False, self._path_handles)

    @staticmethod
    def view_rows(data: FrameData, camera: RenderPath) -> int:
        """Instance rows each shadow view writes after the camera's: every row with a mesh (the
        CPU culls them per view), or in the indirect mode the set-aside casters' alone (the GPU
        culls the camera's rows in place: at a million entities and 4 cascades, 256 MB less)."""
        if isinstance(camera, IndirectPath):
            return len(data.set_aside) if data.set_aside is not None else 0
        return data.all_rows

    @property
    def active(self) -> bool:
        """Whether this frame draws shadow views (after prepare)."""
        return bool(self._inputs)

    @property
    def culls_on_gpu(self) -> bool:
        """Whether this frame's views cull the chunks' rows on the GPU (the indirect mode): the
        chunk jobs then record nothing for them (frame_jobs.py)."""
        return self._gpu_frame and bool(self._inputs)

    @property
    def draws(self) -> int:
        """The last frame's shadow draws: those recorded on the CPU, and those the GPU counted
        in the indirect mode (an earlier frame's unless the frame was read back, as the camera's)."""
        return self._counts[0] + (self.gpu.counts()[0] if self.gpu is not None and self.culls_on_gpu else 0)

    @property
    def triangles(self) -> int:
        """The last frame's shadow triangles, counted as `draws`."""
        return self._counts[1] + (self.gpu.counts()[1] if self.gpu is not None and self.culls_on_gpu else 0)

    def record_chunk(self, chunk: Chunk, camera: Any = None) -> tuple[ChunkResult | None, list[ChunkResult]]:
        """One job: the chunk culled against every view at once (a row's sphere is worked out
        once, not once a view: instance_rows.cull_views), then per view its visible rows written
        and recorded. With `camera` (its path and FrameInputs; the path can record culled rows)
        the camera's view is culled in the same pass: (the camera's result or None, per view)."""
        fused = self._fused
        if fused is not None and (camera is None or fused.with_camera):
            results = fused.record(chunk, camera is not None)
            return (results[0], results[1:]) if camera is not None else (None, results)
        centers, radii, index_counts = self._inputs[0].bounds
        planes = self._planes if camera is not None else self._planes[1:]
        keys = np.empty((len(planes), len(chunk.handle)), np.int32)
        key_counts = np.empty((len(planes), 2 * len(index_counts)), np.int64)
        cull_views(chunk.model, chunk.handle, centers, radii, planes, keys, key_counts)
        path, empty, first = self._recording, ChunkResult(None, 0, 0, 0), int(camera is not None)
        results = [
            path.record_keyed(chunk, view, keys[v], key_counts[v]) if key_counts[v].any() else empty
            for v, view in enumerate(self._inputs, first)
        ]
        if camera is None:
            return None, results
        return camera[0].record_keyed(chunk, camera[1], keys[0], key_counts[0]), results

    def collect(self, results: list[list[ChunkResult]]) -> list[list[Any]]:
        """Per view the secondaries record() executes; the draws and triangles summed."""
        per_view: list[list[Any]] = [[] for _ in self._inputs]
        for per_chunk in results:
            for k, r in enumerate(per_chunk):
                if r.command_buffer is not None:
                    per_view[k].append(r.command_buffer)
                self._counts[0] += r.draws
                self._counts[1] += r.triangles
        return per_view

    light_views = staticmethod(light_views)  # the renderer names each light's views with it

    def gpu_culled(self, secondaries: list[list[Any]]) -> list[list[Any]]:
        """Per view its secondaries, the GPU-culled draws' first in the indirect mode (their
        compute made ready for the frame graph's "shadow_cull" pass)."""
        if self.gpu is None or not self.culls_on_gpu:
            return secondaries
        culled = self.gpu.prepare(self._inputs, self._planes[1:])
        return [([g] if g is not None else []) + s for g, s in zip(culled, secondaries, strict=True)]

    def record(self, cb: Any, ctx: Any, views: list[ShadowView], secondaries: list[list[Any]]) -> None:
        """Each view's layer drawn from its secondaries, in the frame graph's "shadow_maps" pass
        (maps_graph.py: it declares the layers, so the graph places the barriers); the first
        maps were cleared whole when made (gpu/shadow_maps.py), so none is read undefined."""
        assert self.maps is not None
        maps = self.maps
        drawn = {v.layer: s for v, s in zip(views, secondaries, strict=True)}
        sizes = {v.layer: v.resolution for v in views}
        image = maps.image
        assert image is not None
        handle = image.handle
        for layer in drawn:  # each view's corner of its layer (all were cleared when made: ShadowMaps)
            size = min(sizes[layer], maps.resolution)  # as target_state's
            area, token = (0, 0, size, size), (layer, size, handle)  # (new maps: another handle)
            ctx.render_secondaries(drawn.get(layer), token, "shadow_maps", layer, area)

    def destroy(self) -> None:
        self.owned.destroy()
        self.path = self.gpu = self.maps = None
