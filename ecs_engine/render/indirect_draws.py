"""The indirect render mode's GPU side: a compute shader culls, another writes the draw commands,
and vkCmdDrawIndexedIndirectCount draws them.

The CPU chunk jobs write every candidate row (no CPU culling) with its key, mesh * 2 + mirrored,
and count rows per key; from those counts each key gets a region of the `ids` buffer. On the GPU:
1. cull.comp, one invocation per row: bounding sphere against the frustum planes; a visible row
   appends its index to its key's region (an atomic counter per key).
2. compact.comp, one invocation per key: a non-empty key becomes one instanced
   VkDrawIndexedIndirectCommand (first_instance = the region's start), appended to the list of
   its winding; the list lengths are the counts vkCmdDrawIndexedIndirectCount reads.
3. In the frame's secondary: per winding, one vkCmdDrawIndexedIndirectCount over the merged mesh
   buffers; the vertex shader reads instances[ids[gl_InstanceIndex]].

Visible counts exist only on the GPU: they are copied to a mapped buffer and read once the
frame's fence has signalled (an earlier frame's, or this one's after a readback wait).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import UsageError
from ..gpu.memory import DEVICE, HOST, Buffer
from ..gpu.pipeline import compute_pipeline, pipeline_layout

if TYPE_CHECKING:
    from ..gpu.device import Device
    from .mesh_registry import MergedMeshes

KEY_DTYPE = np.dtype([("index_count", np.uint32), ("first_index", np.uint32), ("vertex_offset", np.int32),
                      ("base", np.uint32), ("sphere", np.float32, 4)])
COMMAND_BYTES = 20  # VkDrawIndexedIndirectCommand
STATE_HEADER = 4  # uints before the per-key counters: draw count per winding, 2 unused
CULL_GROUP = 256  # cull.comp local_size_x
COMPACT_GROUP = 64  # compact.comp local_size_x
PUSH_BYTES = 112  # the compute layout's range: 6 planes and 3 uints (cull.comp)
FEATURES = ("drawIndirectCount", "multiDrawIndirect", "drawIndirectFirstInstance")


@dataclass
class _IndirectFrame:
    keys: Buffer  # HOST, KEY_DTYPE per key, written each frame
    ids: Buffer  # DEVICE, one uint per candidate row
    state: Buffer  # DEVICE, draw counts and visible rows per key (zeroed each frame)
    commands: Buffer  # DEVICE, 2 lists of `meshes` commands
    readback: Buffer  # HOST, the state as the frame left it
    key_slots: int  # keys the buffers hold
    row_slots: int
    recorded: bool = False  # `readback` holds a frame's counts
    copy_region: Any = None  # VkBufferCopy* of the whole state buffer
    written: tuple[bytes, int] | None = None  # (key counts, merged meshes) the key table holds


@dataclass
class IndirectCounts:
    visible: int
    draws: int
    triangles: int


def check_support(device: Device) -> None:
    missing = [f for f in FEATURES if not device.features.get(f)]
    if missing:
        raise UsageError(f"{device.info.name} lacks {', '.join(missing)}: the indirect mode needs it; "
                         "use --mode instanced")


class IndirectDraws:
    def __init__(self, device: Device, set_layout: Any, frames: int) -> None:
        check_support(device)
        vk = self.vk = device.vk
        self.device = device
        self.layout = pipeline_layout(device, [set_layout.handle], [(vk.VK_SHADER_STAGE_COMPUTE_BIT, 0, PUSH_BYTES)])
        self.cull = compute_pipeline(device, "cull.comp", self.layout)
        self.compact = compute_pipeline(device, "compact.comp", self.layout)
        self.max_groups = int(device.limits.maxComputeWorkGroupCount[0])
        self.frames = [self._make_frame(2, 1024) for _ in range(frames)]
        # made once: the per-frame calls go straight to vk.lib (see gpu/frames.py)
        self._push = np.zeros(PUSH_BYTES // 4, dtype=np.float32)
        self._push_ptr = vk.ffi.from_buffer(self._push)
        self._offsets = vk.ffi.new("VkDeviceSize[1]", [0])
        compute = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
        shader_rw = vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT
        self._barriers = [_Barrier(vk, *b) for b in (
            (vk.VK_PIPELINE_STAGE_TRANSFER_BIT, compute, vk.VK_ACCESS_TRANSFER_WRITE_BIT, shader_rw),
            (compute, compute, vk.VK_ACCESS_SHADER_WRITE_BIT, shader_rw),
            (compute, vk.VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | vk.VK_PIPELINE_STAGE_VERTEX_SHADER_BIT
             | vk.VK_PIPELINE_STAGE_TRANSFER_BIT, vk.VK_ACCESS_SHADER_WRITE_BIT,
             vk.VK_ACCESS_INDIRECT_COMMAND_READ_BIT | vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_TRANSFER_READ_BIT),
            (vk.VK_PIPELINE_STAGE_TRANSFER_BIT, vk.VK_PIPELINE_STAGE_HOST_BIT, vk.VK_ACCESS_TRANSFER_WRITE_BIT,
             vk.VK_ACCESS_HOST_READ_BIT))]

    def _make_frame(self, keys: int, rows: int) -> _IndirectFrame:
        vk = self.vk
        ssbo = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
        indirect = vk.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT
        return _IndirectFrame(
            keys=Buffer(self.device, KEY_DTYPE.itemsize * keys, ssbo),
            ids=Buffer(self.device, 4 * rows, ssbo, DEVICE),
            state=Buffer(self.device, 4 * (STATE_HEADER + keys), ssbo | indirect | vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                         DEVICE),
            commands=Buffer(self.device, COMMAND_BYTES * keys, ssbo | indirect, DEVICE),
            readback=Buffer(self.device, 4 * (STATE_HEADER + keys), vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST),
            key_slots=keys, row_slots=rows,
            copy_region=vk.ffi.new("VkBufferCopy*", {"srcOffset": 0, "dstOffset": 0, "size": 4 * (STATE_HEADER + keys)}))

    def bindings(self, slot: int) -> list[tuple[int, int, Buffer]]:
        """(binding, descriptor type, buffer) of the frame's buffers in the shared set (4-7)."""
        f = self.frames[slot]
        ssbo = self.vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        return [(4, ssbo, f.ids), (5, ssbo, f.keys), (6, ssbo, f.state), (7, ssbo, f.commands)]

    def ensure_capacity(self, slot: int, keys: int, rows: int) -> bool:
        """Grow the frame's buffers (doubling); True when the descriptor set must be rewritten.
        Safe: the frame's fence has been waited on."""
        f = self.frames[slot]
        if keys <= f.key_slots and rows <= f.row_slots:
            return False
        for b in (f.keys, f.ids, f.state, f.commands, f.readback):
            b.destroy()
        self.frames[slot] = self._make_frame(max(keys, f.key_slots), max(rows, 2 * f.row_slots))
        return True

    def counts(self, slot: int, index_counts: np.ndarray) -> IndirectCounts | None:
        """The visible rows, draws and triangles of the last frame this slot carried, once its
        fence has signalled; None before the slot's first frame."""
        f = self.frames[slot]
        if not f.recorded:
            return None
        raw = f.readback.array(np.uint32, STATE_HEADER + f.key_slots)
        visible = raw[STATE_HEADER : STATE_HEADER + 2 * len(index_counts)].astype(np.int64)
        per_mesh = np.repeat(index_counts // 3, 2)
        return IndirectCounts(int(visible.sum()), int(raw[0]) + int(raw[1]), int((visible * per_mesh).sum()))

    def prepare(self, slot: int, key_counts: np.ndarray, merged: MergedMeshes,
                bounds: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
        """Write the key table: each key's mesh and the start of its region of `ids` (skipped
        when the counts and meshes are those the table already holds)."""
        f = self.frames[slot]
        written = (key_counts.tobytes(), id(merged))
        if f.written == written:
            return
        f.written = written
        centers, radii, index_counts = bounds
        n = len(key_counts)
        table = f.keys.array(KEY_DTYPE, n)
        mesh = np.arange(n) // 2
        table["index_count"] = index_counts[mesh]
        table["first_index"] = merged.first_index[mesh]
        table["vertex_offset"] = merged.vertex_offset[mesh]
        table["base"] = np.concatenate([[0], np.cumsum(key_counts)[:-1]])
        table["sphere"][:, :3] = centers[mesh]
        table["sphere"][:, 3] = radii[mesh]

    def record_compute(self, cb: Any, slot: int, set_array: Any, planes: np.ndarray | None, rows: int,
                       keys: int) -> None:
        """Into the primary, before the render pass: zero the counters, cull, write commands,
        and copy the counters where the CPU can read them. `set_array`: VkDescriptorSet[1]."""
        vk = self.vk
        lib = vk.lib
        f = self.frames[slot]
        to_compute, compute_to_compute, to_draw, to_host = self._barriers
        stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
        # the previous frame in this slot read the commands and ids: its fence covered that
        lib.vkCmdFillBuffer(cb, f.state.handle, 0, f.state.size, 0)
        to_compute.record(lib, cb)
        lib.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.layout, 0, 1, set_array, 0, vk.ffi.NULL)
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.cull)
        push = self._push
        words = push.view(np.uint32)
        words[24] = 0
        if planes is not None:
            push[: 4 * len(planes)] = planes.reshape(-1)
            words[24] = len(planes)
        step = self.max_groups * CULL_GROUP
        for first in range(0, rows, step):
            count = min(step, rows - first)
            words[25] = first + count  # rows below this index exist
            words[26] = first
            lib.vkCmdPushConstants(cb, self.layout, stage, 0, PUSH_BYTES, self._push_ptr)
            lib.vkCmdDispatch(cb, -(-count // CULL_GROUP), 1, 1)
        compute_to_compute.record(lib, cb)
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.compact)
        words[:2] = (keys, keys // 2)
        lib.vkCmdPushConstants(cb, self.layout, stage, 0, 8, self._push_ptr)
        lib.vkCmdDispatch(cb, -(-keys // COMPACT_GROUP), 1, 1)
        to_draw.record(lib, cb)
        lib.vkCmdCopyBuffer(cb, f.state.handle, f.readback.handle, 1, f.copy_region)
        to_host.record(lib, cb)
        f.recorded = True

    def record_draws(self, cb: Any, slot: int, pipelines: tuple[Any, Any], merged: MergedMeshes,
                     key_counts: np.ndarray) -> None:
        """Into the frame's secondary (viewport, scissor and set already bound): one indirect
        count draw per winding that has candidates."""
        vk = self.vk
        lib = vk.lib
        f = self.frames[slot]
        meshes = len(key_counts) // 2
        if merged.vertex_array is None:
            merged.vertex_array = vk.ffi.new("VkBuffer[1]", [merged.vertices.handle])
        lib.vkCmdBindVertexBuffers(cb, 0, 1, merged.vertex_array, self._offsets)
        lib.vkCmdBindIndexBuffer(cb, merged.indices.handle, 0, vk.VK_INDEX_TYPE_UINT32)
        for winding, pipeline in enumerate(pipelines):
            if not key_counts[winding::2].any():
                continue
            lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
            lib.vkCmdDrawIndexedIndirectCount(cb, f.commands.handle, winding * meshes * COMMAND_BYTES,
                                              f.state.handle, 4 * winding, meshes, COMMAND_BYTES)

    def destroy(self) -> None:
        vk = self.vk
        for f in self.frames:
            for b in (f.keys, f.ids, f.state, f.commands, f.readback):
                b.destroy()
        vk.vkDestroyPipeline(self.device.handle, self.cull, None)
        vk.vkDestroyPipeline(self.device.handle, self.compact, None)
        vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)


class _Barrier:
    """A global memory barrier, made once and recorded with a raw call."""

    def __init__(self, vk: Any, src_stage: int, dst_stage: int, src_access: int, dst_access: int) -> None:
        self.stages = (src_stage, dst_stage)
        self.barrier = vk.ffi.new("VkMemoryBarrier*", {"sType": vk.VK_STRUCTURE_TYPE_MEMORY_BARRIER,
                                                       "srcAccessMask": src_access, "dstAccessMask": dst_access})
        self.null = vk.ffi.NULL

    def record(self, lib: Any, cb: Any) -> None:
        lib.vkCmdPipelineBarrier(cb, self.stages[0], self.stages[1], 0, 1, self.barrier, 0, self.null, 0, self.null)
