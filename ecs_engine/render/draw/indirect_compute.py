"""The indirect path's compute for one frame, step by step: each step is recorded by one of the
frame graph's cull passes (cull_pass.py), which declare what the step reads and writes, so the
graph places the barriers between them (there are none here).

The steps, in order: zero the counters; with occlusion culling (culling/occlusion_passes.py) the
early cull, its compact, the early rows' depth, the depth pyramid and the counters zeroed again;
then the cull (the frustum's, or occlusion's late one), compact, and the counters' copy for the
host. `prepare` (the path's finish) fills the push constants once for the frame."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..assets.mesh_registry import MergedMeshes
from ..culling.occlusion_passes import OcclusionPasses
from ..layouts import COMPACT_GROUP, COMPACT_PUSH, CULL_GROUP, CULL_LOD, CULL_PUSH, CULL_SUBPIXEL
from .indirect_draws import IndirectFrame, record_indirect_draws


class IndirectCompute:
    def __init__(self, path: Any) -> None:
        self.path = path  # the IndirectPath: its pipelines, layouts, sets and push constants
        self.vk = path.vk
        self.f: IndirectFrame | None = None
        self.rows = 0
        self.keys = 0
        self.merged: MergedMeshes | None = None
        self.capacity: np.ndarray | None = None
        self.occlusion: OcclusionPasses | None = None  # this frame's: None culls the frustum alone
        self.sets_layout: Any = None  # the compute layout the sets are bound with

    def prepare(
        self,
        f: IndirectFrame,
        frame: Any,
        planes: np.ndarray | None,
        rows: int,
        merged: MergedMeshes,
        capacity: np.ndarray,
        occlusion: OcclusionPasses | None,
    ) -> None:
        """This frame's inputs: `capacity` per key of every draw mesh (levels of detail too), as
        key_capacities gives it; `occlusion`: the culling method's passes or None."""
        path = self.path
        self.f, self.rows, self.merged, self.capacity, self.occlusion = f, rows, merged, capacity, occlusion
        self.keys = len(capacity)
        self.sets_layout = path.compute_layout if occlusion is None else occlusion.layout
        _, width, height = frame.target.key
        push = path._push
        push["plane_count"] = 0
        if planes is not None:
            push["planes"][0, : len(planes)] = planes
            push["plane_count"] = len(planes)
        lod = CULL_LOD if frame.lod and merged.lod_levels.any() else 0
        push["occlusion"] = (width, height, 0, lod)  # cull.comp: the levels of detail's projection
        if occlusion is not None:
            subpixel = CULL_SUBPIXEL if occlusion.samples == 1 else 0  # MSAA samples lie off the centres
            push["occlusion"] = (width, height, len(occlusion.levels), subpixel | lod)

    # ------------------------------------------------------------------ the steps
    def zero(self, cb: Any) -> None:
        """The counters (the previous frame in this slot read them: its fence covered that) and,
        new, occlusion's visibility."""
        assert self.f is not None
        state = self.f.state
        self.vk.lib.vkCmdFillBuffer(cb, state.handle, 0, state.size, 0)
        if self.occlusion is not None:
            self.occlusion.zero_visibility(cb)

    def cull(self, cb: Any, late: bool) -> None:
        """One cull over every row: the frustum's, occlusion's early one, or (`late`) its late one."""
        vk = self.vk
        path = self.path
        self._bind(cb)
        occlusion = self.occlusion
        pipeline = path.cull if occlusion is None else occlusion.late if late else occlusion.early
        lib = vk.lib
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, pipeline)
        push, rows = path._push, self.rows
        step = path.max_groups * CULL_GROUP  # dispatches of at most maxComputeWorkGroupCount groups
        for first in range(0, rows, step):
            count = min(step, rows - first)
            push["row_end"] = first + count  # rows below this index exist
            push["first_row"] = first
            lib.vkCmdPushConstants(
                cb, path.compute_layout, vk.VK_SHADER_STAGE_COMPUTE_BIT, 0, CULL_PUSH.size, path._push_ptr
            )
            lib.vkCmdDispatch(cb, -(-count // CULL_GROUP), 1, 1)

    def compact(self, cb: Any) -> None:
        """The non-empty keys' draw commands."""
        vk = self.vk
        path = self.path
        lib = vk.lib
        self._bind(cb)
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, path.compact)
        keys = self.keys
        path._compact_push["key_count"], path._compact_push["mesh_count"] = keys, keys // 2
        lib.vkCmdPushConstants(
            cb, path.compute_layout, vk.VK_SHADER_STAGE_COMPUTE_BIT, 0, COMPACT_PUSH.size, path._compact_ptr
        )
        lib.vkCmdDispatch(cb, -(-keys // COMPACT_GROUP), 1, 1)

    def depth(self, cb: Any, ctx: Any, name: str) -> None:
        """The early rows' depth into the graph's image `name` (declared DEPTH_WRITE, cleared to
        reverse-Z's far): the camera's set 0, this frame's set 1, every draw mesh's keys as the
        scene's draws (compact wrote the lists `keys // 2` apart)."""
        vk = self.vk
        path, occlusion, f = self.path, self.occlusion, self.f
        assert occlusion is not None and f is not None and self.merged is not None and self.capacity is not None
        ctx.begin_rendering(depth=name, token=occlusion.depth_token)
        vk.lib.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, path.layout, 0, 2, path._sets, 0, vk.ffi.NULL
        )
        pipelines = occlusion.pipelines
        record_indirect_draws(vk, cb, pipelines, self.merged, self.capacity, f.commands, f.state, path._offsets)
        ctx.end_rendering()

    def pyramid(self, cb: Any) -> None:
        assert self.occlusion is not None
        self._bind(cb)
        self.occlusion.record_pyramid(cb)

    def readback(self, cb: Any) -> None:
        """The counters copied where the host reads them (after the frame's fence)."""
        f = self.f
        assert f is not None
        self.vk.lib.vkCmdCopyBuffer(cb, f.state.handle, f.readback.handle, 1, f.copy_region)

    def _bind(self, cb: Any) -> None:
        vk = self.vk
        lib = vk.lib
        compute = vk.VK_PIPELINE_BIND_POINT_COMPUTE
        lib.vkCmdBindDescriptorSets(cb, compute, self.sets_layout, 0, 2, self.path._sets, 0, vk.ffi.NULL)
        if self.occlusion is not None:
            self.occlusion.bind(cb)
