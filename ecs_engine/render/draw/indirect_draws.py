"""The indirect path's per-slot buffers and what the camera's draws share with the shadow views'
(shadow_indirect.py): the counters' layout, the per-winding indirect draws and the compute
passes' barriers; and the device features the path needs."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import UsageError
from ...gpu.barrier import Barrier
from ...gpu.device import Device
from ...gpu.memory import Buffer
from ..assets.mesh_registry import MergedMeshes
from ..layouts import DRAW_COMMAND, DRAW_STATE, UINT_BYTES

STATE_HEADER = DRAW_STATE.size // UINT_BYTES  # uints before the per-key counters
FEATURES = ("drawIndirectCount", "multiDrawIndirect", "drawIndirectFirstInstance")


@dataclass
class IndirectFrame:
    descriptor_set: Any  # set 1
    keys: Buffer  # HOST, KEY_INFO per key, written each frame
    ids: Buffer  # DEVICE, one uint per candidate row
    state: Buffer  # DEVICE, DRAW_STATE header then visible rows per key (zeroed each frame)
    commands: Buffer  # DEVICE, 2 lists of `meshes` commands
    readback: Buffer  # HOST, the state as the frame left it
    key_slots: int  # keys the buffers hold
    # per mesh, the triangles of one instance, of the frame whose counts `readback` holds (None:
    # no frame yet); its length says how many keys that frame had (meshes may be added since)
    recorded: np.ndarray | None = None
    copy_region: Any = None  # VkBufferCopy* of the whole state buffer
    written: tuple[bytes, int] | None = None  # (key counts, merged meshes) the key table holds
    previous: tuple[int, int, int] | None = None  # the counts of the slot's last frame, read at begin_frame
    # this frame's candidate rows per key and count (finish): what the shadow views cull
    key_counts: np.ndarray | None = None
    candidates: int = 0


def record_indirect_draws(
    vk: Any,
    cb: Any,
    pipelines: tuple[Any, Any],
    merged: MergedMeshes,
    key_counts: np.ndarray,
    commands: Buffer,
    state: Buffer,
    offsets: Any,
) -> None:
    """One vkCmdDrawIndexedIndirectCount per winding that has candidates, over the merged mesh
    buffers, reading compact.comp's `commands` and the counts in `state` (the camera's draws, and
    each GPU-culled shadow view's: shadow_indirect.py)."""
    lib = vk.lib
    meshes = len(key_counts) // 2
    if merged.vertex_array is None:
        merged.vertex_array = vk.ffi.new("VkBuffer[1]", [merged.vertices.handle])
    lib.vkCmdBindVertexBuffers(cb, 0, 1, merged.vertex_array, offsets)
    lib.vkCmdBindIndexBuffer(cb, merged.indices.handle, 0, vk.VK_INDEX_TYPE_UINT32)
    for winding, pipeline in enumerate(pipelines):
        if not key_counts[winding::2].any():
            continue
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
        lib.vkCmdDrawIndexedIndirectCount(
            cb,
            commands.handle,
            winding * meshes * DRAW_COMMAND.size,
            state.handle,
            DRAW_STATE.offset("draw_counts") + UINT_BYTES * winding,
            meshes,
            DRAW_COMMAND.size,
        )


def key_capacities(key_counts: np.ndarray, merged: MergedMeshes) -> np.ndarray:
    """Per key of every draw mesh, the rows its region of `ids` must hold: a mesh's keys their
    rows, each of its levels' keys the same (every row may be drawn at any level). The meshes'
    keys come first, so their regions start where they did without levels (the shadow views'
    ids hold those alone)."""
    owners = merged.owners[merged.count :]
    capacity = np.zeros(2 * merged.draw_meshes, dtype=np.int64)
    capacity[: len(key_counts)] = key_counts
    capacity[len(key_counts) :: 2] = key_counts[2 * owners]
    capacity[len(key_counts) + 1 :: 2] = key_counts[2 * owners + 1]
    return capacity


def check_support(device: Device) -> None:
    missing = [f for f in FEATURES if not device.features.get(f)]
    if missing:
        raise UsageError(
            f"{device.info.name} lacks {', '.join(missing)}: the indirect mode needs it; use --mode instanced"
        )


def compute_barriers(vk: Any) -> list[Barrier]:
    """The compute passes' barriers, in order: the counters zeroed -> cull, cull -> compact, the
    commands written -> the draws (and the counters' copy), the copy -> the host's read; for
    occlusion culling, the early draws and the pyramid -> the cleared counters and the late cull."""
    compute = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
    shader_rw = vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT
    return [
        Barrier(vk, *b)
        for b in (
            (vk.VK_PIPELINE_STAGE_TRANSFER_BIT, compute, vk.VK_ACCESS_TRANSFER_WRITE_BIT, shader_rw),
            (compute, compute, vk.VK_ACCESS_SHADER_WRITE_BIT, shader_rw),
            (
                compute,
                vk.VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT
                | vk.VK_PIPELINE_STAGE_VERTEX_SHADER_BIT
                | vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                vk.VK_ACCESS_SHADER_WRITE_BIT,
                vk.VK_ACCESS_INDIRECT_COMMAND_READ_BIT | vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_TRANSFER_READ_BIT,
            ),
            (
                vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                vk.VK_PIPELINE_STAGE_HOST_BIT,
                vk.VK_ACCESS_TRANSFER_WRITE_BIT,
                vk.VK_ACCESS_HOST_READ_BIT,
            ),
            (
                vk.VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT
                | vk.VK_PIPELINE_STAGE_VERTEX_SHADER_BIT
                | vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
                | vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                compute | vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                vk.VK_ACCESS_SHADER_WRITE_BIT | vk.VK_ACCESS_TRANSFER_WRITE_BIT,
                shader_rw | vk.VK_ACCESS_TRANSFER_WRITE_BIT,
            ),
        )
    ]
