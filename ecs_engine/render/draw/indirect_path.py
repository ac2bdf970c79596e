"""The `indirect` render path: compute shaders cull and write the draw commands, and
vkCmdDrawIndexedIndirectCount draws them.

The CPU chunk jobs write every candidate row (no CPU culling) with its key, mesh * 2 + mirrored,
and count rows per key; from those counts each key gets a region of the `ids` buffer. On the GPU:
1. cull.comp, one invocation per row: bounding sphere against the frustum planes; a visible row
   appends its index to its key's region (an atomic counter per key).
2. compact.comp, one invocation per key: a non-empty key becomes one instanced DrawCommand
   (first_instance = the region's start), appended to the list of its winding; the list lengths
   are the counts vkCmdDrawIndexedIndirectCount reads.
3. In the frame's one secondary: per winding, one vkCmdDrawIndexedIndirectCount over the merged
   mesh buffers; the vertex shader reads instances[ids[gl_InstanceIndex]].

The path's buffers are descriptor set 1 (layouts.py). Visible counts exist only on the GPU: they
are copied to a mapped buffer and read once the frame's fence has signalled (an earlier frame's,
or this one's after a readback wait).

Shadow views (shadow_indirect.py) are culled by the same shaders over the same rows, each view
with its own set 1 naming this frame's key table; rows of NotShadowCaster chunks carry
ROW_NOT_CASTER in misc.w, which their cull leaves out.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import UsageError
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_buffers
from ...gpu.memory import DEVICE, HOST, Buffer
from ...gpu.pipeline import compute_pipeline, pipeline_layout
from ...gpu.secondary import end_command_buffer
from ..assets.mesh_registry import MergedMeshes
from ..culling.occlusion_passes import OcclusionPasses
from ..extract.frame_data import NOT_CASTER, NOT_RECEIVER, Chunk
from ..layouts import (
    BINDING_COMMANDS,
    BINDING_DRAW_STATE,
    BINDING_IDS,
    BINDING_KEYS,
    COMPACT_PUSH,
    CULL_PUSH,
    DRAW_COMMAND,
    DRAW_STATE,
    KEY_INFO,
    ROW_LEVEL_SHIFT,
    ROW_NOT_CASTER,
    UINT_BYTES,
)
from .chunk_paths import mesh_pipelines
from .indirect_compute import IndirectCompute
from .indirect_draws import (
    STATE_HEADER,
    IndirectFrame,
    check_support,
    key_capacities,
    record_indirect_draws,
)
from .instance_rows import write_rows
from .path import ChunkResult, FrameInputs, MeshBounds, PathContext
from .path_pipelines import PipelinesPerTarget


class IndirectPath(PipelinesPerTarget):
    name = "indirect"
    recorder = "gpu"
    uses_recorder = False  # compute shaders write the draws

    def __init__(self, ctx: PathContext, recorder: str | None = None) -> None:
        check_support(ctx.device)  # before anything is created
        self.ctx = ctx
        self.vk = ctx.device.vk
        self.frames: list[IndirectFrame] = []
        self.occlusion: OcclusionPasses | None = None  # asked for by --culling occlusion (culling/occlusion.py)
        try:
            self._build(ctx)
        except BaseException:
            self.destroy()  # what was made so far
            raise

    def _build(self, ctx: PathContext) -> None:
        device, vk = ctx.device, self.vk
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        stages = vk.VK_SHADER_STAGE_VERTEX_BIT | vk.VK_SHADER_STAGE_COMPUTE_BIT
        bindings = (BINDING_IDS, BINDING_KEYS, BINDING_DRAW_STATE, BINDING_COMMANDS)
        self.set_layout = DescriptorSetLayout(device, [(b, ssbo, stages) for b in bindings])
        n = ctx.frames_in_flight
        self.pool = DescriptorPool(device, n, {ssbo: len(bindings) * n})
        sets = [ctx.frame_set_layout, self.set_layout.handle]
        self.layout = pipeline_layout(device, sets)
        self.compute_layout = pipeline_layout(device, sets, [(vk.VK_SHADER_STAGE_COMPUTE_BIT, 0, CULL_PUSH.size)])
        self._first_pipelines()
        self.cull = compute_pipeline(device, "cull.comp", self.compute_layout)
        self.compact = compute_pipeline(device, "compact.comp", self.compute_layout)
        self.max_groups = int(device.limits.maxComputeWorkGroupCount[0])
        for _ in range(n):
            self.frames.append(self._make_frame(self.pool.allocate(self.set_layout), 2, 1024))
        # made once: the per-frame calls go straight to vk.lib (see gpu/frames.py)
        self._push = np.zeros(1, dtype=CULL_PUSH.dtype)
        self._compact_push = np.zeros(1, dtype=COMPACT_PUSH.dtype)
        self._push_ptr = vk.ffi.from_buffer(self._push)
        self._compact_ptr = vk.ffi.from_buffer(self._compact_push)
        self._sets = vk.ffi.new("VkDescriptorSet[2]")
        self._offsets = vk.ffi.new("VkDeviceSize[1]", [0])
        self.compute = IndirectCompute(self)  # the frame's steps, each a cull pass's (cull_pass.py)
        self.pending: bool | None = None  # finish made the compute ready; the cull passes record it

    # ---------------------------------------------------------------- buffers
    def _make_frame(self, descriptor_set: Any, keys: int, rows: int) -> IndirectFrame:
        vk = self.vk
        device = self.ctx.device
        ssbo = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
        indirect = vk.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT
        state_bytes = DRAW_STATE.size + UINT_BYTES * keys
        f = IndirectFrame(
            descriptor_set=descriptor_set,
            keys=Buffer(device, KEY_INFO.size * keys, ssbo),
            ids=Buffer(device, UINT_BYTES * rows, ssbo, DEVICE),
            state=Buffer(device, state_bytes, ssbo | indirect | vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, DEVICE),
            commands=Buffer(device, DRAW_COMMAND.size * keys, ssbo | indirect, DEVICE),
            readback=Buffer(device, state_bytes, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST),
            key_slots=keys,
            copy_region=vk.ffi.new("VkBufferCopy*", {"srcOffset": 0, "dstOffset": 0, "size": state_bytes}),
        )
        self._write_set(f)
        return f

    def _write_set(self, f: IndirectFrame) -> None:
        ssbo = self.vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        write_buffers(
            self.ctx.device,
            f.descriptor_set,
            [
                (BINDING_IDS, ssbo, f.ids),
                (BINDING_KEYS, ssbo, f.keys),
                (BINDING_DRAW_STATE, ssbo, f.state),
                (BINDING_COMMANDS, ssbo, f.commands),
            ],
        )

    def _ensure_capacity(self, slot: int, keys: int, rows: int) -> None:
        """Grow the frame's buffers; safe: the frame's fence has been waited on."""
        if rows > 1 << ROW_LEVEL_SHIFT:  # a row's ids entry holds its index below the level it is drawn at
            raise UsageError(f"the indirect mode draws at most {1 << ROW_LEVEL_SHIFT:,} rows a frame, not {rows:,}")
        f = self.frames[slot]
        if keys > f.key_slots:
            for b in (f.keys, f.ids, f.state, f.commands, f.readback):
                b.destroy()
            previous = f.previous  # read at begin_frame, before the buffers went
            f = self.frames[slot] = self._make_frame(f.descriptor_set, keys, max(rows, f.ids.size // UINT_BYTES))
            f.previous = previous
        ids = f.ids.grown(UINT_BYTES * rows)
        if ids is not f.ids:
            f.ids = ids
            self._write_set(f)

    # -------------------------------------------------------------- the path
    def rows_needed(self, candidates: int) -> int:
        return candidates

    def begin_frame(self, frame: FrameInputs) -> None:
        """The slot's last counts, before this frame overwrites them (a read-back frame reads its
        own counts after the wait instead)."""
        f = self.frames[frame.slot]
        f.previous = None if frame.readback else self._read_counts(frame.slot)

    def record_chunk(self, chunk: Chunk, frame: FrameInputs) -> ChunkResult:
        """One job: write every row (the GPU culls) and count rows per key."""
        centers, radii, index_counts = frame.bounds
        rows = frame.instances[chunk.offset : chunk.offset + len(chunk.handle)]
        key_counts = np.zeros(2 * len(index_counts), dtype=np.int64)
        write_rows(
            chunk.model, chunk.handle, chunk.material, centers, radii, None, frame.material_count, rows, key_counts,
            chunk.extra,
        )  # fmt: skip
        if chunk.flags & NOT_RECEIVER:
            rows["misc"][:, 2] |= 1  # no shadow falls on these (mesh_vertex.glsl)
        if chunk.flags & NOT_CASTER:
            rows["misc"][:, 3] |= ROW_NOT_CASTER  # the shadow views' cull leaves these out (cull.comp)
        return ChunkResult(None, 0, 0, 0, key_counts)

    def finish(self, cb: Any, frame: FrameInputs, results: list[ChunkResult], candidates: int) -> list[Any]:
        """The compute made ready for the frame graph's cull passes (indirect_compute.py, recorded
        by cull_pass.py's passes) and the one secondary that draws what they write."""
        key_counts = np.zeros(2 * len(frame.bounds[2]), dtype=np.int64)  # the meshes' keys: rows as written
        for r in results:
            if r.key_counts is not None:
                key_counts += r.key_counts
        if frame.lod:  # levels of detail only for the meshes drawn (mesh_registry.py)
            self.ctx.meshes.build_levels(np.flatnonzero(key_counts.reshape(-1, 2).sum(axis=1)))
        merged = self.ctx.meshes.merged()
        capacity = key_capacities(key_counts, merged)  # every draw mesh's keys: rows they may get
        keys = len(capacity)
        self._ensure_capacity(frame.slot, keys, int(capacity.sum()))
        self._write_key_table(frame.slot, capacity, merged, frame.bounds)
        f = self.frames[frame.slot]
        f.key_counts, f.candidates = key_counts, candidates  # what the shadow views cull (shadow_indirect.py)
        self._sets[0], self._sets[1] = frame.descriptor_set, f.descriptor_set
        planes = None if frame.planes is None else frame.planes.astype(np.float32)
        _, width, height = frame.target.key
        occlusion = frame.data.culling.gpu(self, width, height, candidates)  # None: the frustum test alone
        self.compute.prepare(f, frame, planes, candidates, merged, capacity, occlusion)
        self.pending = True  # the graph's cull passes record it (cull_pass.py)
        f.recorded = merged.index_count // 3  # the triangles the counts will weigh, per draw mesh
        vk = self.vk
        lib = vk.lib
        secondary = self.ctx.secondaries.begin(frame.slot, frame.target.secondary_begin)
        lib.vkCmdSetViewport(secondary, 0, 1, frame.target.viewport_ptr)
        lib.vkCmdSetScissor(secondary, 0, 1, frame.target.area_ptr)
        lib.vkCmdBindDescriptorSets(
            secondary, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 2, self._sets, 0, vk.ffi.NULL
        )
        self._record_draws(secondary, frame.slot, merged, capacity)
        end_command_buffer(vk, secondary)
        return [secondary]

    def counts(self, frame: FrameInputs, results: list[ChunkResult]) -> tuple[int, int, int]:
        """Counted on the GPU: this frame's when it was waited for, else the slot's previous one."""
        f = self.frames[frame.slot]
        counts = self._read_counts(frame.slot) if frame.readback else f.previous
        return counts if counts is not None else (0, 0, 0)

    # ------------------------------------------------------------ GPU work
    def _read_counts(self, slot: int) -> tuple[int, int, int] | None:
        """(draws, visible rows, triangles) of the last frame this slot carried, once its fence
        has signalled; None before the slot's first frame. Read with that frame's mesh list."""
        f = self.frames[slot]
        if f.recorded is None:
            return None
        per_key = np.repeat(f.recorded, 2)
        raw = f.readback.array(np.uint32, STATE_HEADER + len(per_key))
        visible = raw[STATE_HEADER:].astype(np.int64)
        return int(raw[0]) + int(raw[1]), int(visible.sum()), int((visible * per_key).sum())

    def _write_key_table(self, slot: int, capacity: np.ndarray, merged: MergedMeshes, bounds: MeshBounds) -> None:
        """Each key's draw mesh, the start of its region of `ids` and, for a mesh's keys, its
        sphere and levels of detail (skipped when the table already holds these)."""
        f = self.frames[slot]
        written = (capacity.tobytes(), id(merged))
        if f.written == written:
            return
        f.written = written
        centers, radii, _ = bounds
        n = len(capacity)
        table = f.keys.array(KEY_INFO.dtype, n)
        draw = np.arange(n) // 2
        owner = merged.owners[draw]  # the mesh whose rows the key draws
        table["index_count"] = merged.index_count[draw]
        table["first_index"] = merged.first_index[draw]
        table["vertex_offset"] = merged.vertex_offset[draw]
        table["base"] = np.concatenate([[0], np.cumsum(capacity)[:-1]])
        table["sphere"][:, :3] = centers[owner]
        table["sphere"][:, 3] = radii[owner]
        own = draw < merged.count  # the rows' own keys carry the levels; a level's keys none
        table["lod"] = 0
        table["lod"][own, 0] = merged.lod_first[owner[own]]
        table["lod"][own, 1] = merged.lod_levels[owner[own]]
        table["lod_error"] = 0.0
        table["lod_error"][own] = merged.lod_error[owner[own]]

    def draw_buffers(self, slot: int) -> dict[str, Any]:
        """The slot's buffers the compute passes write and the draws read, by graph name."""
        f = self.frames[slot]
        return {"draws.ids": f.ids, "draws.commands": f.commands, "draws.state": f.state, "draws.readback": f.readback}

    def occlusion_passes(self) -> OcclusionPasses:
        """Occlusion culling's passes (culling/occlusion.py asks), made on first use against this
        path's layouts, and destroyed with it."""
        if self.occlusion is None:
            self.occlusion = OcclusionPasses(self.ctx, [self.ctx.frame_set_layout, self.set_layout.handle], self.layout)
        return self.occlusion

    def _record_draws(self, cb: Any, slot: int, merged: MergedMeshes, key_counts: np.ndarray) -> None:
        """Into the frame's secondary (viewport, scissor and sets already bound)."""
        f = self.frames[slot]
        record_indirect_draws(self.vk, cb, self.pipelines, merged, key_counts, f.commands, f.state, self._offsets)

    def _make_pipelines(self, ctx: PathContext) -> tuple[Any, Any]:
        return mesh_pipelines(ctx, self.layout, "mesh_indirect.vert")

    def destroy(self) -> None:
        """Also for a path half built (its constructor failed): what exists goes."""
        vk = self.vk
        handle = self.ctx.device.handle
        for f in self.frames:
            for b in (f.keys, f.ids, f.state, f.commands, f.readback):
                b.destroy()
        self.frames = []
        if self.__dict__.get("occlusion") is not None:
            self.occlusion.destroy()  # type: ignore[union-attr]
            self.occlusion = None
        if "layout" in self.__dict__:
            self._destroy_pipelines()
        for name in ("cull", "compact"):
            made = self.__dict__.pop(name, None)
            for pipeline in made if isinstance(made, tuple) else (made,) if made is not None else ():
                vk.vkDestroyPipeline(handle, pipeline, None)
        for name in ("layout", "compute_layout"):
            layout = self.__dict__.pop(name, None)
            if layout is not None:
                vk.vkDestroyPipelineLayout(handle, layout, None)
        for name in ("pool", "set_layout"):
            owned = self.__dict__.pop(name, None)
            if owned is not None:
                owned.destroy()
