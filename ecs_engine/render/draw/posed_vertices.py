"""Deformed rows' vertices as the GPU poses them, read back: shaders/posed_vertices.comp runs the
vertex shaders' own skin and morph functions (shaders/deform.glsl) over every vertex of a
drawn frame's instance row and writes the render-relative position and the normal of each.

The vertex shaders' output cannot be read back (no transform feedback here), so this is how the
engine shows what its skinning computes on the device: the tests hold it to the glTF
specification's formulas written out in NumPy, vertex by vertex, for every clip at many times.
It reads the frame slot's own buffers (its instance rows, joint rows and the registry's skin
data), as the frame's draws did."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ...gpu.barrier import Barrier
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_set
from ...gpu.memory import HOST, Buffer
from ...gpu.owned import Owned
from ...gpu.pipeline import compute_pipeline, pipeline_layout
from ..layouts import INSTANCE, POSED_GROUP

ROW_WORDS = INSTANCE.size // 4  # an instance row in 32-bit words; its misc.y (mesh * 2 + mirrored) is word 13
PUSH_BYTES = 12  # row, vertices, first


def deformed_rows(frame: Any, rows: int) -> np.ndarray:
    """The indices of a frame slot's first `rows` instance rows that are skinned or morphed
    (misc.z >> 1 or misc.w >> 1 set, extract/skins.py)."""
    words = frame.instances.array(np.uint32, (rows, ROW_WORDS))
    return np.flatnonzero((words[:, 14] >> 1 != 0) | (words[:, 15] >> 1 != 0))


class PosedVertices:
    """The pipeline (set 0: a frame slot's set, as the draws bind it; set 1: a mesh's vertex
    buffer and the output) and `read`, one submission that waits for the GPU."""

    def __init__(self, device: Any, frame_layout: Any) -> None:
        vk = device.vk
        self.device = device
        stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        self.owned = owned = Owned(device)
        try:
            self.set_layout = owned.add(DescriptorSetLayout(device, [(0, ssbo, stage), (1, ssbo, stage)]))
            handle = device.handle
            layout = self.layout = pipeline_layout(
                device, [frame_layout, self.set_layout.handle], [(stage, 0, PUSH_BYTES)]
            )
            owned.add(layout, lambda: vk.vkDestroyPipelineLayout(handle, layout, None))
            pipeline = self.pipeline = compute_pipeline(device, "posed_vertices.comp", layout)
            owned.add(pipeline, lambda: vk.vkDestroyPipeline(handle, pipeline, None))
        except BaseException:
            owned.destroy()
            raise
        self._after = Barrier(
            vk, vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, vk.VK_PIPELINE_STAGE_HOST_BIT,
            vk.VK_ACCESS_SHADER_WRITE_BIT, vk.VK_ACCESS_HOST_READ_BIT,
        )  # fmt: skip

    def read(self, frame: Any, meshes: Any, rows: Sequence[int]) -> list[np.ndarray]:
        """Per row of `frame` (a FrameResources whose frame the GPU has finished), its mesh's
        vertices posed: (V, 2, 4) float32, the render-relative position (w 1) and the normal
        (the normal matrix's, not normalised; w 0). `meshes`: the MeshRegistry drawn from."""
        vk = self.device.vk
        lib = vk.lib
        words = frame.instances.array(np.uint32, (max(rows, default=0) + 1, ROW_WORDS))
        handles = [int(words[r, 13]) >> 1 for r in rows]
        counts = [len(meshes[h].data.positions) for h in handles]
        firsts = np.r_[0, np.cumsum(counts)].astype(int)
        total = max(int(firsts[-1]), 1)
        distinct = sorted(set(handles))
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        scope = Owned(self.device)
        try:
            out = scope.add(Buffer(self.device, total * 32, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, HOST))
            pool = scope.add(DescriptorPool(self.device, max(len(distinct), 1), {ssbo: 2 * max(len(distinct), 1)}))
            sets = {}
            for h in distinct:
                sets[h] = pool.allocate(self.set_layout)
                write_set(self.device, sets[h], storage_buffers=[(0, meshes[h].vertices), (1, out)])
            push = np.zeros(3, np.uint32)
            point, stage = vk.VK_PIPELINE_BIND_POINT_COMPUTE, vk.VK_SHADER_STAGE_COMPUTE_BIT

            def record(cb: Any) -> None:
                lib.vkCmdBindPipeline(cb, point, self.pipeline)
                for row, h, count, first in zip(rows, handles, counts, firsts.tolist()):
                    both = vk.ffi.new("VkDescriptorSet[2]", [frame.descriptor_set, sets[h]])
                    lib.vkCmdBindDescriptorSets(cb, point, self.layout, 0, 2, both, 0, vk.ffi.NULL)
                    push[:] = (row, count, first)
                    lib.vkCmdPushConstants(cb, self.layout, stage, 0, PUSH_BYTES, vk.ffi.from_buffer(push))
                    lib.vkCmdDispatch(cb, -(-count // POSED_GROUP), 1, 1)
                self._after.record(lib, cb)

            self.device.submit_once(record)
            posed = out.array(np.float32, (total, 2, 4)).copy()
        finally:
            scope.destroy()
        return [posed[a:b] for a, b in zip(firsts[:-1].tolist(), firsts[1:].tolist())]

    def destroy(self) -> None:
        self.owned.destroy()  # the pipeline, its layout, the set layout
