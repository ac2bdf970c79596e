"""Meshes uploaded once to device-local memory and shared: entities hold only a handle."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .gpu.memory import Buffer, upload
from .mesh_data import MeshData

if TYPE_CHECKING:
    from .gpu.device import Device

VERTEX_STRIDE = 24  # position xyz, normal xyz, float32


@dataclass
class GpuMesh:
    data: MeshData
    vertices: Buffer
    indices: Buffer
    index_count: int


class MeshRegistry:
    def __init__(self, device: Device) -> None:
        self.device = device
        self._meshes: list[GpuMesh] = []
        self._by_data: dict[int, int] = {}

    def add(self, mesh: MeshData) -> int:
        """Upload `mesh` (once: the same MeshData object gives the same handle)."""
        key = id(mesh)
        if key in self._by_data and self._meshes[self._by_data[key]].data is mesh:
            return self._by_data[key]
        vk = self.device.vk
        interleaved = np.empty((len(mesh.positions), 6), dtype=np.float32)
        interleaved[:, :3] = mesh.positions
        interleaved[:, 3:] = mesh.normals
        vertices = upload(self.device, interleaved, vk.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT)
        indices = upload(self.device, mesh.indices, vk.VK_BUFFER_USAGE_INDEX_BUFFER_BIT)
        handle = len(self._meshes)
        self._meshes.append(GpuMesh(mesh, vertices, indices, len(mesh.indices)))
        self._by_data[key] = handle
        return handle

    def __getitem__(self, handle: int) -> GpuMesh:
        return self._meshes[handle]

    def __len__(self) -> int:
        return len(self._meshes)

    def triangles(self, handle: int) -> int:
        return self._meshes[handle].index_count // 3

    def bind(self, cb: Any, handle: int) -> GpuMesh:
        vk = self.device.vk
        mesh = self._meshes[handle]
        vk.vkCmdBindVertexBuffers(cb, 0, 1, [mesh.vertices.handle], [0])
        vk.vkCmdBindIndexBuffer(cb, mesh.indices.handle, 0, vk.VK_INDEX_TYPE_UINT32)
        return mesh

    def destroy(self) -> None:
        for mesh in self._meshes:
            mesh.vertices.destroy()
            mesh.indices.destroy()
        self._meshes.clear()
        self._by_data.clear()
