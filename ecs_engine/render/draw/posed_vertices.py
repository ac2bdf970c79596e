"""Deformed rows' vertices as the GPU poses them: shaders/posed_vertices.comp runs the vertex
shaders' own skin and morph functions (shaders/deform.glsl) over every vertex of an instance
row's mesh and writes the render-relative positions (and, when asked, the normals).

Two users: the ray-traced shadows build a skinned or morphed row's bottom level from its posed
positions (render/raytracing/deformed.py), and `read` brings a drawn frame's posed vertices back
to the CPU. The vertex shaders' output cannot be read back (no transform feedback here), so that
is how the tests hold the GPU's skinning to the glTF specification's formulas, vertex by vertex.
"""

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
PUSH_WORDS = ROW_WORDS + 3  # the row, then vertices, first, normals
POSED_WITH_NORMALS = 32  # bytes a vertex with `normals`: two vec4 (position, normal)
POSED_POSITIONS = 16  # bytes a vertex without: one vec4


def deformed_rows(frame: Any, rows: int) -> np.ndarray:
    """The indices of a frame slot's first `rows` instance rows that are skinned or morphed
    (misc.z >> 1 or misc.w >> 1 set, extract/skins.py)."""
    words = frame.instances.array(np.uint32, (rows, ROW_WORDS))
    return np.flatnonzero((words[:, 14] >> 1 != 0) | (words[:, 15] >> 1 != 0))


class PosedVertices:
    """The pipeline (set 0: a frame slot's set, for its joint rows and the registry's skin data;
    set 1: a mesh's vertex buffer and the output), `record_row` and `read`."""

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
                device, [frame_layout, self.set_layout.handle], [(stage, 0, 4 * PUSH_WORDS)]
            )
            owned.add(layout, lambda: vk.vkDestroyPipelineLayout(handle, layout, None))
            pipeline = self.pipeline = compute_pipeline(device, "posed_vertices.comp", layout)
            owned.add(pipeline, lambda: vk.vkDestroyPipeline(handle, pipeline, None))
        except BaseException:
            owned.destroy()
            raise
        self._push = np.zeros(PUSH_WORDS, np.uint32)
        self._sets = vk.ffi.new("VkDescriptorSet[2]")
        self._after = Barrier(
            vk, vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, vk.VK_PIPELINE_STAGE_HOST_BIT,
            vk.VK_ACCESS_SHADER_WRITE_BIT, vk.VK_ACCESS_HOST_READ_BIT,
        )  # fmt: skip

    def mesh_sets(self, pool: DescriptorPool, meshes: Any, handles: Sequence[int], out: Buffer) -> dict[int, Any]:
        """Per mesh handle, a set from `pool` (2 storage buffers each) naming its vertices and `out`."""
        sets = {}
        for h in sorted(set(handles)):
            sets[h] = pool.allocate(self.set_layout)
            write_set(self.device, sets[h], storage_buffers=[(0, meshes[h].vertices), (1, out)])
        return sets

    def bind(self, cb: Any) -> None:
        self.device.vk.lib.vkCmdBindPipeline(cb, self.device.vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.pipeline)

    def record_row(
        self, cb: Any, frame_set: Any, mesh_set: Any, row: np.ndarray, count: int, first: int, normals: bool
    ) -> None:
        """After `bind`: pose the `count` vertices of instance row `row` (ROW_WORDS uint32, as the
        frame's instance buffer holds it) into the output from vertex `first` on."""
        vk = self.device.vk
        lib = vk.lib
        point = vk.VK_PIPELINE_BIND_POINT_COMPUTE
        self._sets[0], self._sets[1] = frame_set, mesh_set
        lib.vkCmdBindDescriptorSets(cb, point, self.layout, 0, 2, self._sets, 0, vk.ffi.NULL)
        push = self._push
        push[:ROW_WORDS] = row
        push[ROW_WORDS:] = (count, first, int(normals))
        lib.vkCmdPushConstants(
            cb, self.layout, vk.VK_SHADER_STAGE_COMPUTE_BIT, 0, 4 * PUSH_WORDS, vk.ffi.from_buffer(push)
        )
        lib.vkCmdDispatch(cb, -(-count // POSED_GROUP), 1, 1)

    def read(self, frame: Any, meshes: Any, rows: Sequence[int]) -> list[np.ndarray]:
        """Per row of `frame` (a FrameResources whose frame the GPU has finished), its mesh's
        vertices posed: (V, 2, 4) float32, the render-relative position (w 1) and the normal
        (the normal matrix's, not normalised; w 0). `meshes`: the MeshRegistry drawn from."""
        vk = self.device.vk
        words = frame.instances.array(np.uint32, (max(rows, default=0) + 1, ROW_WORDS))
        handles = [int(words[r, 13]) >> 1 for r in rows]
        counts = [len(meshes[h].data.positions) for h in handles]
        firsts = np.r_[0, np.cumsum(counts)].astype(int)
        total = max(int(firsts[-1]), 1)
        distinct = max(len(set(handles)), 1)
        scope = Owned(self.device)
        try:
            usage = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
            out = scope.add(Buffer(self.device, total * POSED_WITH_NORMALS, usage, HOST))
            pool = scope.add(
                DescriptorPool(self.device, distinct, {vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER: 2 * distinct})
            )
            sets = self.mesh_sets(pool, meshes, handles, out)

            def record(cb: Any) -> None:
                self.bind(cb)
                for row, h, count, first in zip(rows, handles, counts, firsts.tolist()):
                    self.record_row(cb, frame.descriptor_set, sets[h], words[row], count, first, True)
                self._after.record(vk.lib, cb)

            self.device.submit_once(record)
            posed = out.array(np.float32, (total, 2, 4)).copy()
        finally:
            scope.destroy()
        return [posed[a:b] for a, b in zip(firsts[:-1].tolist(), firsts[1:].tolist())]

    def destroy(self) -> None:
        self.owned.destroy()  # the pipeline, its layout, the set layout
