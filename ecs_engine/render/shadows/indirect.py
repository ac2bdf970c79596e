"""The indirect mode's shadow views, culled and drawn on the GPU (issue 15).

In the indirect mode the CPU writes every candidate row once, unculled, into the frame's instance
buffer (indirect_path.py). Each shadow view (a cascade, a spot light's map, a cube face) culls
those same rows with the camera path's shaders, against its own planes; no row is written twice.
After the camera's path has written its key table and recorded its own passes (its finish),
`record` adds to the primary, before the shadow views' renderings:

1. every view's draw state zeroed; barrier (transfer -> compute);
2. per view, cull.comp over the camera's candidate rows [0, candidates) with the view's planes
   (padded to six) and pc.skip = ROW_NOT_CASTER: rows of NotShadowCaster chunks (their misc.w,
   written by the path's record_chunk) cast nothing; barrier (compute -> compute);
3. per view, compact.comp: its non-empty keys become its draw commands; barrier (compute ->
   indirect draws, vertex shaders, transfer);
4. every view's draw state copied to a mapped buffer (the draws and triangles in FrameStats,
   read once the slot's fence has signalled, as the camera's); barrier (transfer -> host).

It returns per view a secondary for the view's shadow rendering: per winding one
vkCmdDrawIndexedIndirectCount with depth-only pipelines (shadow_indirect.vert: the row is
instances[ids[gl_InstanceIndex]]; where some material is alpha-masked shadow_indirect_cutout.vert
and shadow_cutout.frag, which cut the material's holes), the rasteriser's depth bias of the CPU
shadow pipelines (chunk_paths.SHADOW_DEPTH_BIAS), the view's set 0 (its globals hold the light's
matrices, shadow_pass.view_inputs) and its set 1.

Buffers: per frame slot and view, a set 1 of the camera path's layout naming the view's own `ids`
(a uint per candidate row), draw state and commands, and the camera's key table of that slot
(read only: a key's region of `ids` is sized by the candidates, which no view exceeds). Buffers of
their own rather than regions of one: cull.comp and compact.comp stay as the camera runs them
(regions would need per-view offsets in the shaders, or dynamic descriptors and other pipelines),
and the sets are written only when a buffer is replaced (grown, or the camera's key table made
anew).

The set-aside rows (blended, wireframe, points materials: frame_data.SetAsideRows.casters) are not
among the path's rows: the CPU shadow jobs still draw them into the views (frame_jobs.py), next to
these draws.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...gpu.barrier import Barrier
from ...gpu.descriptors import DescriptorPool, write_buffers
from ...gpu.memory import DEVICE, HOST, Buffer
from ...gpu.owned import Owned
from ...gpu.pipeline import AttachmentFormats
from ...gpu.secondary import end_command_buffer
from ..draw.chunk_paths import shadow_pipelines
from ..draw.indirect_draws import STATE_HEADER, compute_barriers, record_indirect_draws
from ..draw.indirect_path import IndirectPath
from ..draw.path import FrameInputs
from ..layouts import (
    BINDING_COMMANDS,
    BINDING_DRAW_STATE,
    BINDING_IDS,
    BINDING_KEYS,
    COMPACT_GROUP,
    COMPACT_PUSH,
    CULL_GROUP,
    CULL_PUSH,
    DRAW_COMMAND,
    DRAW_STATE,
    ROW_NOT_CASTER,
    UINT_BYTES,
)


@dataclass
class _ViewBuffers:
    """One view's set 1 in one frame slot and the buffers of its own it names."""

    descriptor_set: Any
    ids: Buffer  # DEVICE: a uint per candidate row (cull.comp's output)
    state: Buffer  # DEVICE: DRAW_STATE header, then visible rows per key
    commands: Buffer  # DEVICE: 2 lists of `key_slots // 2` commands
    key_slots: int
    named: tuple[Buffer, ...] = ()  # (ids, keys, state, commands) the set names


class IndirectShadows:
    """The shadow views of one IndirectPath (made again with the path: shadow_pass.py)."""

    def __init__(self, camera: IndirectPath, formats: AttachmentFormats) -> None:
        ctx = camera.ctx
        self.camera = camera
        self.device = ctx.device
        self.vk = vk = ctx.device.vk
        self.secondaries = ctx.secondaries
        self.pool: DescriptorPool | None = None
        # the pipelines and readbacks live as long as this; the pool and the views' buffers go
        # together when the pool grows (_pooled, destroyed first)
        self.owned = Owned(self.device)
        self._pooled = Owned(self.device)
        self._pool_sets = 0  # view sets the pool holds per frame slot
        self._views: list[list[_ViewBuffers]] = [[] for _ in range(ctx.frames_in_flight)]
        self._readback: list[Buffer | None] = [None] * ctx.frames_in_flight
        # per slot, what its readback holds: (views, state bytes a view, triangles per key), or None
        self._counted: list[tuple[int, int, np.ndarray] | None] = [None] * ctx.frames_in_flight
        self._slot, self._waited, self._previous = 0, False, (0, 0)
        self._counted_now = False  # this frame recorded counts into the slot's readback
        shadow_ctx = replace(ctx, formats=formats, gbuffer=False, shadow=True, samples=1, fill="solid")
        self.pipelines = shadow_pipelines(shadow_ctx, camera.layout, "mesh_indirect.vert")
        for pipeline in self.pipelines:
            self.owned.add(pipeline, _pipeline_destroyer(self.device, pipeline))
        self._push = np.zeros(1, dtype=CULL_PUSH.dtype)
        self._compact_push = np.zeros(1, dtype=COMPACT_PUSH.dtype)
        self._push_ptr = vk.ffi.from_buffer(self._push)
        self._compact_ptr = vk.ffi.from_buffer(self._compact_push)
        self._offsets = vk.ffi.new("VkDeviceSize[1]", [0])
        barriers = compute_barriers(vk)
        compute, transfer = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, vk.VK_PIPELINE_STAGE_TRANSFER_BIT
        to_copy = Barrier(vk, compute, transfer, vk.VK_ACCESS_SHADER_WRITE_BIT, vk.VK_ACCESS_TRANSFER_READ_BIT)
        self._barriers = [barriers[0], barriers[1], to_copy, barriers[3]]  # the counters -> their copy: third
        self.pending: tuple | None = None  # prepare's, for record_compute

    # -------------------------------------------------------------- per frame
    def begin_frame(self, slot: int, readback: bool) -> None:
        """After the slot's fence: the counts its last frame left (a read-back frame reads its
        own after the wait instead)."""
        self._slot, self._waited = slot, readback
        self._previous = (0, 0) if readback else self._read_counts(slot)
        self._counted_now = False

    def counts(self) -> tuple[int, int]:
        """(draws, triangles) the GPU counted over the views: this frame's when it was waited
        for, else the slot's previous frame's (like the camera's, indirect_path.py)."""
        if self._waited and self._counted_now:
            return self._read_counts(self._slot)
        return self._previous

    def prepare(self, views: list[FrameInputs], planes: np.ndarray) -> list[Any]:
        """The views' cull and commands made ready for the frame graph's "shadow_cull" pass
        (maps_graph.py: record_compute); per view the secondary drawing them in its rendering
        (None: nothing to draw). `views`: their FrameInputs (their set 0, target); `planes`:
        (V, 24), padded_planes'."""
        slot = self._slot
        self.pending = None  # nothing to cull unless made ready below
        frame = self.camera.frames[slot]  # its finish wrote this frame's key table
        key_counts, rows = frame.key_counts, frame.candidates
        self._counted[slot] = None
        if key_counts is None or rows == 0 or not views:
            return [None] * len(views)
        keys = len(key_counts)
        buffers = self._ensure(slot, len(views), keys, rows, frame.keys)
        sets = [
            self.vk.ffi.new("VkDescriptorSet[2]", [v.descriptor_set, b.descriptor_set]) for v, b in zip(views, buffers)
        ]
        self.pending = (slot, buffers, sets, planes, rows, keys)
        triangles = np.repeat(views[0].bounds[2] // 3, 2)[:keys]
        self._counted[slot] = (len(views), DRAW_STATE.size + UINT_BYTES * keys, triangles)
        self._counted_now = True
        return [self._record_draws(slot, view, b, s, key_counts) for view, b, s in zip(views, buffers, sets)]

    def draw_buffers(self) -> dict[str, Any]:
        """This frame's views' buffers that the compute writes and their draws read, by graph
        name ("shadow_draws.<view>.ids" ...), and the counters' host copy; none when nothing
        is culled."""
        if self.pending is None:
            return {}
        slot, buffers = self.pending[0], self.pending[1]
        kinds = ("ids", "state", "commands")
        named = {f"shadow_draws.{k}.{n}": getattr(b, n) for k, b in enumerate(buffers) for n in kinds}
        return {**named, "shadow_draws.readback": self._readback[slot]}

    def record_compute(self, cb: Any) -> None:
        """The views' cull, compaction and counters' copy (prepare made them ready)."""
        assert self.pending is not None
        pending, self.pending = self.pending, None
        self._record_compute(cb, *pending)

    # ------------------------------------------------------------ GPU work
    def _record_compute(
        self, cb: Any, slot: int, buffers: list[_ViewBuffers], sets: list[Any], planes: np.ndarray, rows: int, keys: int
    ) -> None:
        vk, camera = self.vk, self.camera
        lib = vk.lib
        compute, stage = vk.VK_PIPELINE_BIND_POINT_COMPUTE, vk.VK_SHADER_STAGE_COMPUTE_BIT
        layout = camera.compute_layout
        to_compute, compute_to_compute, to_copy, to_host = self._barriers[:4]
        for b in buffers:  # the previous frame in this slot read them: its fence covered that
            lib.vkCmdFillBuffer(cb, b.state.handle, 0, b.state.size, 0)
        to_compute.record(lib, cb)
        lib.vkCmdBindPipeline(cb, compute, camera.cull)
        push = self._push
        push["plane_count"], push["skip"] = 6, ROW_NOT_CASTER
        step = camera.max_groups * CULL_GROUP
        for view_sets, view_planes in zip(sets, planes):
            lib.vkCmdBindDescriptorSets(cb, compute, layout, 0, 2, view_sets, 0, vk.ffi.NULL)
            push["planes"][0] = view_planes.reshape(6, 4)
            for first in range(0, rows, step):
                count = min(step, rows - first)
                push["row_end"], push["first_row"] = first + count, first
                lib.vkCmdPushConstants(cb, layout, stage, 0, CULL_PUSH.size, self._push_ptr)
                lib.vkCmdDispatch(cb, -(-count // CULL_GROUP), 1, 1)
        compute_to_compute.record(lib, cb)
        lib.vkCmdBindPipeline(cb, compute, camera.compact)
        self._compact_push["key_count"], self._compact_push["mesh_count"] = keys, keys // 2
        lib.vkCmdPushConstants(cb, layout, stage, 0, COMPACT_PUSH.size, self._compact_ptr)
        for view_sets in sets:
            lib.vkCmdBindDescriptorSets(cb, compute, layout, 0, 2, view_sets, 0, vk.ffi.NULL)
            lib.vkCmdDispatch(cb, -(-keys // COMPACT_GROUP), 1, 1)
        to_copy.record(lib, cb)  # the draws' barrier is the graph's (their reads are declared)
        readback = self._readback[slot]
        assert readback is not None
        size = DRAW_STATE.size + UINT_BYTES * keys
        for k, b in enumerate(buffers):
            region = vk.ffi.new("VkBufferCopy*", {"srcOffset": 0, "dstOffset": k * size, "size": size})
            lib.vkCmdCopyBuffer(cb, b.state.handle, readback.handle, 1, region)
        to_host.record(lib, cb)

    def _record_draws(self, slot: int, view: FrameInputs, b: _ViewBuffers, sets: Any, key_counts: np.ndarray) -> Any:
        """The view's secondary: per winding with candidates, one indirect count draw."""
        vk, camera = self.vk, self.camera
        lib = vk.lib
        merged = camera.ctx.meshes.merged()  # the camera's finish made it for this frame
        target = view.target
        cb = self.secondaries.begin(slot, target.secondary_begin)
        lib.vkCmdSetViewport(cb, 0, 1, target.viewport_ptr)
        lib.vkCmdSetScissor(cb, 0, 1, target.area_ptr)
        lib.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, camera.layout, 0, 2, sets, 0, vk.ffi.NULL)
        record_indirect_draws(vk, cb, self.pipelines, merged, key_counts, b.commands, b.state, self._offsets)
        end_command_buffer(vk, cb)
        return cb

    def _read_counts(self, slot: int) -> tuple[int, int]:
        """(draws, triangles) of the views of the last frame this slot carried, once its fence
        has signalled."""
        counted, readback = self._counted[slot], self._readback[slot]
        if counted is None or readback is None:
            return 0, 0
        views, size, triangles = counted
        raw = readback.array(np.uint32, (views, size // UINT_BYTES))
        visible = raw[:, STATE_HEADER:].astype(np.int64)
        return int(raw[:, :2].sum()), int((visible * triangles).sum())

    # ---------------------------------------------------------------- buffers
    def _ensure(self, slot: int, views: int, keys: int, rows: int, key_table: Buffer) -> list[_ViewBuffers]:
        """The slot's first `views` view buffers, holding `keys` keys and `rows` rows, their sets
        naming them and `key_table`; safe: the slot's fence has been waited on."""
        if self.pool is None or views > self._pool_sets:
            self._grow_pool(views)
        assert self.pool is not None
        vk = self.vk
        out = self._views[slot]
        while len(out) < views:
            out.append(_ViewBuffers(self.pool.allocate(self.camera.set_layout), *self._key_buffers(1024, keys), keys))
        for b in out[:views]:
            if keys > b.key_slots:
                self._pooled.release(b.state)
                self._pooled.release(b.commands)
                b.ids, b.state, b.commands = self._key_buffers(b.ids.size // UINT_BYTES, keys, b.ids)
                b.key_slots = keys
            b.ids = b.ids.grown(UINT_BYTES * rows, self._pooled)
            named = (b.ids, key_table, b.state, b.commands)
            if len(b.named) != len(named) or any(x is not y for x, y in zip(named, b.named)):
                kind = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
                bindings = (BINDING_IDS, BINDING_KEYS, BINDING_DRAW_STATE, BINDING_COMMANDS)
                write_buffers(self.device, b.descriptor_set, [(n, kind, x) for n, x in zip(bindings, named)])
                b.named = named
        size = views * (DRAW_STATE.size + UINT_BYTES * keys)
        readback = self._readback[slot]
        if readback is None:
            readback = self.owned.add(Buffer(self.device, size, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST))
        self._readback[slot] = readback.grown(size, self.owned)
        return out[:views]

    def _key_buffers(self, rows: int, keys: int, ids: Buffer | None = None) -> tuple[Buffer, Buffer, Buffer]:
        """(ids, state, commands) for `keys` keys (`ids` kept when given)."""
        vk, device, owned = self.vk, self.device, self._pooled
        ssbo, indirect = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, vk.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT
        if ids is None:
            ids = owned.add(Buffer(device, UINT_BYTES * rows, ssbo, DEVICE))
        state_usage = ssbo | indirect | vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT
        state = owned.add(Buffer(device, DRAW_STATE.size + UINT_BYTES * keys, state_usage, DEVICE))
        commands = owned.add(Buffer(device, DRAW_COMMAND.size * keys, ssbo | indirect, DEVICE))
        return ids, state, commands

    def _grow_pool(self, views: int) -> None:
        """A pool for `views` sets per frame slot (the old sets and buffers go: the device is
        waited for)."""
        self.device.wait_idle()
        self._release()
        per_slot = max(8, views)
        count = per_slot * len(self._views)
        sizes = {self.vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER: 4 * count}
        self.pool = self._pooled.add(DescriptorPool(self.device, count, sizes))
        self._pool_sets = per_slot

    def _release(self) -> None:
        self._pooled.destroy()  # the views' buffers, then the pool (their sets with it)
        for slot in self._views:
            slot.clear()
        self._counted = [None] * len(self._views)
        self.pool = None

    def destroy(self) -> None:
        """The caller waited for the device (frames in flight may use the pipelines)."""
        self._release()
        self.owned.destroy()  # the readbacks, then the pipelines
        self._readback = [None] * len(self._readback)
        self.__dict__.pop("pipelines", None)


def _pipeline_destroyer(device: Any, pipeline: Any) -> Callable[[], None]:
    return lambda: device.vk.vkDestroyPipeline(device.handle, pipeline, None)
