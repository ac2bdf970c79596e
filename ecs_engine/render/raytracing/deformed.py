"""Ray-traced shadows of skinned and morphed meshes (render/raytracing/shadows.py): a mesh's own
bottom level holds its rest pose, which no ray may see on a deformed row. Each such row of the
frame gets a bottom level of its own instead, built from its vertices as this frame poses them
(render/draw/posed_vertices.py: the vertex shaders' own skin and morph code, in a compute pass)
and refitted on the frames after, rebuilt every REBUILD_EVERY frames (a refit's quality drifts
as limbs move). The posed vertices are already in the render-relative world, so the row's
top-level instance names its bottom level with the identity transform.

One set of posed vertices and bottom levels serves every frame slot: only the GPU writes them,
in queue order, behind a barrier against the last frame's rays and builds; it is made again
(after the device is idle) when the frame's deformed rows name other meshes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...gpu.acceleration import MeshInput, Scratch, Structure, build_info, build_sizes, functions, triangle_geometry
from ...gpu.acceleration_structure import ray_input_usage
from ...gpu.barrier import Barrier
from ...gpu.descriptors import DescriptorPool
from ...gpu.memory import DEVICE, Buffer
from ...gpu.owned import Owned
from ..draw.posed_vertices import POSED_POSITIONS, ROW_WORDS, PosedVertices
from ..extract.frame_data import Chunk

REBUILD_EVERY = 30  # frames between full builds of the deformed rows' bottom levels (refits in between)
IDENTITY_3X4 = np.eye(4, dtype=np.float32)[:3]


@dataclass
class _Levels:
    """What one key (the deformed rows' meshes, in row order) needs: the posed vertices, the
    bottom levels and their scratch, a descriptor set per mesh, and the builds' arguments."""

    owned: Owned
    posed: Buffer
    structures: list[Structure]
    sets: dict[int, Any]
    infos: Any
    pointers: Any
    keep: list[Any]  # the geometries and ranges the infos point at
    firsts: list[int]  # each row's first vertex in `posed`
    built: bool = False


class DeformedLevels:
    def __init__(self, device: Any, frame_layout: Any) -> None:
        vk, lib = device.vk, device.vk.lib
        self.device = device
        self.posed = PosedVertices(device, frame_layout)
        self.fns = functions(device)
        self._key: tuple[int, ...] | None = None
        self._levels: _Levels | None = None
        self._rows = np.zeros((0, ROW_WORDS), np.uint32)  # this frame's deformed rows, as instance rows
        self._since_build = REBUILD_EVERY
        build, rays = (
            lib.VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
            lib.VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
        )
        compute = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
        as_read, as_write = (
            lib.VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR,
            lib.VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
        )
        read, write = vk.VK_ACCESS_SHADER_READ_BIT, vk.VK_ACCESS_SHADER_WRITE_BIT
        # the last frame's rays and builds are done with the vertices and levels rewritten now
        self._before = Barrier(vk, rays | build, compute | build, as_read | read, write | as_write)
        self._posed = Barrier(vk, compute, build, write, read)  # the posed vertices, to the builds
        self._built = Barrier(vk, build, build | rays, as_write, as_read)  # the levels, to the top level and rays

    def plan(self, chunks: list[Chunk], meshes: Any) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """Before the instances are written: per chunk with deformed rows (by its id), the rows'
        indices in it and their bottom levels' addresses. Makes the levels again when the rows
        name other meshes than the last frame's."""
        found: list[tuple[Chunk, np.ndarray]] = []
        for chunk in chunks:
            if chunk.extra is not None:
                rows = np.flatnonzero(chunk.extra != 0)
                if len(rows):
                    found.append((chunk, rows))
        if not found:
            self._rows = self._rows[:0]
            return {}
        handles = np.concatenate([chunk.handle[rows] for chunk, rows in found]).astype(np.int64)
        key = tuple(handles.tolist())
        if key != self._key:
            self._make(key, meshes)
        self._rows = np.concatenate([_instance_rows(chunk, rows) for chunk, rows in found])
        assert self._levels is not None
        addresses = np.array([s.address for s in self._levels.structures], np.uint64)
        out, at = {}, 0
        for chunk, rows in found:
            out[id(chunk)] = (rows, addresses[at : at + len(rows)])
            at += len(rows)
        return out

    def record(self, cb: Any, frame_set: Any, meshes: Any) -> None:
        """Before the top level's build: pose the planned rows' vertices and build or refit
        their bottom levels. `frame_set`: the slot's frame set (this frame's joint rows)."""
        levels = self._levels
        if levels is None or not len(self._rows):
            return
        lib = self.device.vk.lib
        self._before.record(lib, cb)
        self.posed.bind(cb)
        for row, first in zip(self._rows, levels.firsts, strict=True):
            handle = int(row[13]) >> 1
            count = len(meshes[handle].data.positions)
            self.posed.record_row(cb, frame_set, levels.sets[handle], row, count, first, False)
        self._posed.record(lib, cb)
        refit = levels.built and self._since_build < REBUILD_EVERY
        mode = (
            lib.VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR
            if refit
            else lib.VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR
        )
        null = self.device.vk.ffi.NULL
        for i, structure in enumerate(levels.structures):
            levels.infos[i].mode = mode
            levels.infos[i].srcAccelerationStructure = structure.handle if refit else null
        self.fns.build(cb, len(levels.structures), levels.infos, levels.pointers)
        self._built.record(lib, cb)
        levels.built = True
        self._since_build = self._since_build + 1 if refit else 1

    def _make(self, key: tuple[int, ...], meshes: Any) -> None:
        """The posed vertices, bottom levels, scratch and sets for rows of meshes `key`."""
        self.device.wait_idle()  # frames in flight trace the levels replaced here
        self._drop()
        vk, lib, ffi = self.device.vk, self.device.vk.lib, self.device.vk.ffi
        counts = [len(meshes[h].data.positions) for h in key]
        firsts = np.r_[0, np.cumsum(counts)].astype(int).tolist()
        owned = Owned(self.device)
        try:
            usage = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | ray_input_usage(self.device)
            posed = owned.add(Buffer(self.device, max(firsts[-1], 1) * POSED_POSITIONS, usage, DEVICE))
            distinct = len(set(key))
            pool = owned.add(
                DescriptorPool(self.device, distinct, {vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER: 2 * distinct})
            )
            sets = self.posed.mesh_sets(pool, meshes, key, posed)
            level = lib.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR
            flags = (
                lib.VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR
                | lib.VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR
            )
            infos = ffi.new("VkAccelerationStructureBuildGeometryInfoKHR[]", len(key))
            ranges = ffi.new("VkAccelerationStructureBuildRangeInfoKHR[]", len(key))
            keep: list[Any] = [infos, ranges]
            structures, offsets, total = [], [], 0
            align = self.device.ray_tracing.scratch_alignment
            for i, h in enumerate(key):
                gpu_mesh = meshes[h]
                triangles = gpu_mesh.index_count // 3
                at = firsts[i] * POSED_POSITIONS
                source = MeshInput(posed, counts[i], POSED_POSITIONS, gpu_mesh.indices, gpu_mesh.index_count, at)
                geometry = triangle_geometry(self.device, ffi, source)
                info = build_info(self.device, ffi, level, flags, geometry)
                size, build_scratch, update_scratch = build_sizes(self.device, info, triangles)
                structures.append(owned.add(Structure(self.device, level, size)))
                info.dstAccelerationStructure = structures[-1].handle
                infos[i] = info[0]
                ranges[i].primitiveCount = triangles
                keep += [geometry, info]
                offsets.append(total)
                total += -(-max(build_scratch, update_scratch) // align) * align
            scratch = owned.add(Scratch(self.device, total))
            for i, offset in enumerate(offsets):
                infos[i].scratchData.deviceAddress = scratch.address + offset
            pointers = ffi.new("VkAccelerationStructureBuildRangeInfoKHR*[]", [ranges + i for i in range(len(key))])
        except BaseException:
            owned.destroy()
            raise
        self._levels = _Levels(owned, posed, structures, sets, infos, pointers, keep, firsts[:-1])
        self._key = key

    def _drop(self) -> None:
        if self._levels is not None:
            self._levels.owned.destroy()
        self._levels, self._key = None, None

    def destroy(self) -> None:
        self._drop()
        self.posed.destroy()


def _instance_rows(chunk: Chunk, rows: np.ndarray) -> np.ndarray:
    """A chunk's `rows` as the instance rows the vertex shaders read (layouts.INSTANCE): model
    rows 0-2, then misc: material, mesh * 2, and the deform bits of misc.z and misc.w."""
    out = np.zeros((len(rows), ROW_WORDS), np.uint32)
    out[:, :12] = np.ascontiguousarray(chunk.model[rows, :3, :], np.float32).reshape(len(rows), 12).view(np.uint32)
    out[:, 12] = chunk.material[rows]
    out[:, 13] = chunk.handle[rows].astype(np.uint32) << 1
    assert chunk.extra is not None
    extra = chunk.extra[rows]
    out[:, 14] = (extra & np.uint64(0xFFFFFFFF)).astype(np.uint32)
    out[:, 15] = (extra >> np.uint64(32)).astype(np.uint32)
    return out
