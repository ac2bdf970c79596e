"""Acceleration structures (VK_KHR_acceleration_structure) for ray tracing: a bottom level per
mesh, built once on the GPU and compacted, and a top level over instance rows, built or
updated inside a frame's command buffer.

The extension's entry points, one structure in its buffer, scratch buffers and the build info
and sizes are acceleration_structure.py's (re-exported here), with why every call is a raw cffi
call reading constants from `vk.lib`.

Instance rows (`AS_INSTANCE`, 64 bytes, VkAccelerationStructureInstanceKHR): a row-major 3x4
transform (the instance rows' own model-row layout), a 24-bit custom index with an 8-bit mask,
a 24-bit shader-binding-table offset with 8 bits of flags, the bottom level's device address.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .acceleration_structure import (
    AccelerationFunctions,
    Scratch,
    Structure,
    build_info,
    build_sizes,
    functions,
    ray_input_usage,
)
from .barrier import Barrier
from .frames import check
from .memory import Buffer
from .owned import Owned

__all__ = ["AS_INSTANCE", "MeshInput", "TopLevel", "build_bottom_levels", "triangle_geometry"]
# acceleration_structure.py's, imported from here
__all__ += ["AccelerationFunctions", "Scratch", "Structure", "build_info", "build_sizes", "functions"]
__all__ += ["ray_input_usage"]

AS_INSTANCE = np.dtype(
    [
        ("transform", "<f4", (3, 4)),
        ("index_mask", "<u4"),  # custom index (bits 0-23) | mask << 24
        ("sbt_flags", "<u4"),  # shader binding table offset (bits 0-23) | flags << 24
        ("blas", "<u8"),  # the bottom level's device address (0: the instance is inactive)
    ]
)
assert AS_INSTANCE.itemsize == 64


@dataclass(frozen=True)
class MeshInput:
    """One mesh's triangles for a bottom level: float32 positions at `position_offset` of each
    `stride`-byte vertex, uint32 indices (buffers made with `ray_input_usage`)."""

    vertices: Buffer
    vertex_count: int
    stride: int
    indices: Buffer
    index_count: int
    position_offset: int = 0


def triangle_geometry(device: Any, ffi: Any, mesh: MeshInput) -> Any:
    lib = device.vk.lib
    geometry = ffi.new("VkAccelerationStructureGeometryKHR*")
    geometry.sType = lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR
    geometry.geometryType = lib.VK_GEOMETRY_TYPE_TRIANGLES_KHR
    geometry.flags = lib.VK_GEOMETRY_OPAQUE_BIT_KHR  # shadow rays need no any-hit call
    tri = geometry.geometry.triangles
    tri.sType = lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR
    tri.vertexFormat = lib.VK_FORMAT_R32G32B32_SFLOAT
    tri.vertexData.deviceAddress = mesh.vertices.address + mesh.position_offset
    tri.vertexStride = mesh.stride
    tri.maxVertex = max(mesh.vertex_count - 1, 0)
    tri.indexType = lib.VK_INDEX_TYPE_UINT32
    tri.indexData.deviceAddress = mesh.indices.address
    return geometry


def build_bottom_levels(
    device: Any, meshes: Sequence[MeshInput], compact: bool = True, submit: Callable[[Any], Any] | None = None
) -> list[Structure]:
    """Bottom levels for `meshes`, built in one submit, then (with `compact`) copied into
    structures of their compacted size in a second one; the full-size ones are freed. `submit`
    records and submits the build, waiting for it (device.submit_once; bench/raytracing.py
    passes one that times it)."""
    if not meshes:
        return []
    vk, lib, ffi = device.vk, device.vk.lib, device.vk.ffi
    fns = functions(device)
    level = lib.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR
    flags = lib.VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR
    if compact:
        flags |= lib.VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR
    keep = [triangle_geometry(device, ffi, m) for m in meshes]
    infos = ffi.new("VkAccelerationStructureBuildGeometryInfoKHR[]", len(meshes))
    ranges = ffi.new("VkAccelerationStructureBuildRangeInfoKHR[]", len(meshes))
    made: list[Structure] = []
    scratch = None
    try:
        offsets, total = [], 0
        align = device.ray_tracing.scratch_alignment
        for i, (mesh, geometry) in enumerate(zip(meshes, keep)):
            info = build_info(device, ffi, level, flags, geometry)
            size, build_scratch, _ = build_sizes(device, info, mesh.index_count // 3)
            made.append(Structure(device, level, size))
            info.dstAccelerationStructure = made[-1].handle
            infos[i] = info[0]
            ranges[i].primitiveCount = mesh.index_count // 3
            offsets.append(total)
            total += -(-build_scratch // align) * align
        scratch = Scratch(device, total)
        for i, offset in enumerate(offsets):
            infos[i].scratchData.deviceAddress = scratch.address + offset
        pointers = ffi.new("VkAccelerationStructureBuildRangeInfoKHR*[]", [ranges + i for i in range(len(meshes))])
        query = None
        if compact:
            query = vk.vkCreateQueryPool(
                device.handle,
                vk.VkQueryPoolCreateInfo(
                    queryType=lib.VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, queryCount=len(meshes)
                ),
                None,
            )
        try:

            def record(cb: Any) -> None:
                fns.build(cb, len(meshes), infos, pointers)
                if query is not None:
                    stage = lib.VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR
                    built = Barrier(
                        vk,
                        stage,
                        stage,
                        lib.VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
                        lib.VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR,
                    )
                    built.record(lib, cb)
                    lib.vkCmdResetQueryPool(cb, query, 0, len(meshes))
                    handles = ffi.new("VkAccelerationStructureKHR[]", [s.handle for s in made])
                    fns.write_properties(
                        cb, len(meshes), handles, lib.VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, query, 0
                    )

            (submit or device.submit_once)(record)
            if query is not None:
                sizes = ffi.new("uint64_t[]", len(meshes))
                check(
                    vk,
                    lib.vkGetQueryPoolResults(
                        device.handle,
                        query,
                        0,
                        len(meshes),
                        8 * len(meshes),
                        sizes,
                        8,
                        vk.VK_QUERY_RESULT_64_BIT | vk.VK_QUERY_RESULT_WAIT_BIT,
                    ),
                )
                made = _compacted(device, made, [int(s) for s in sizes])
        finally:
            if query is not None:
                vk.vkDestroyQueryPool(device.handle, query, None)
    except BaseException:
        for s in made:
            s.destroy()
        raise
    finally:
        if scratch is not None:
            scratch.destroy()
    return made


def _compacted(device: Any, built: list[Structure], sizes: list[int]) -> list[Structure]:
    """Copies of `built` at their compacted sizes; the originals destroyed."""
    lib, ffi = device.vk.lib, device.vk.ffi
    small: list[Structure] = []
    try:
        for structure, size in zip(built, sizes):
            small.append(Structure(device, structure.level, size))
        copies = [
            ffi.new(
                "VkCopyAccelerationStructureInfoKHR*",
                {
                    "sType": lib.VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR,
                    "src": src.handle,
                    "dst": dst.handle,
                    "mode": lib.VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR,
                },
            )
            for src, dst in zip(built, small)
        ]
        copy = functions(device).copy
        device.submit_once(lambda cb: [copy(cb, info) for info in copies])
    except BaseException:
        for s in small:
            s.destroy()
        raise
    finally:
        for s in built:
            s.destroy()
    return small


class TopLevel:
    """A top-level structure over at most `capacity` AS_INSTANCE rows read from a buffer's device
    address, built (or updated, where allowed) by `record` in a command buffer."""

    def __init__(self, device: Any, capacity: int) -> None:
        lib, ffi = device.vk.lib, device.vk.ffi
        self.device = device
        self.fns = functions(device)
        self.level = lib.VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR
        self.flags = (
            lib.VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR
            | lib.VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR
        )
        geometry = self._geometry = ffi.new("VkAccelerationStructureGeometryKHR*")
        geometry.sType = lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR
        geometry.geometryType = lib.VK_GEOMETRY_TYPE_INSTANCES_KHR
        geometry.geometry.instances.sType = lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR
        self._info = build_info(device, ffi, self.level, self.flags, geometry)
        self._range = ffi.new("VkAccelerationStructureBuildRangeInfoKHR[1]")
        self._ranges = ffi.new("VkAccelerationStructureBuildRangeInfoKHR*[1]", [self._range])
        stages = (
            lib.VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
            lib.VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
        )
        read, write = (
            lib.VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR,
            lib.VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
        )
        # before: the last frame's rays read it (the same queue, earlier submits); after: this frame's
        self._before = Barrier(device.vk, stages[1], stages[0], read, read | write)
        self._after = Barrier(device.vk, stages[0], stages[1], write, read)
        self.built_count = -1  # instances of the last build (an update must keep the count)
        self.capacity = 0
        self.structure: Structure | None = None
        self.scratch: Scratch | None = None
        self._parts = Owned(device)  # the structure and its scratch, made again together by reserve
        self.reserve(capacity)

    def reserve(self, capacity: int) -> bool:
        """Room for `capacity` instances (doubling); True when the structure was made again (its
        handle and address changed: descriptors naming it must be written again). Call it only
        when the GPU no longer uses the structure."""
        if capacity <= self.capacity and self.structure is not None:
            return False
        capacity = max(int(capacity), 2 * self.capacity, 64)
        size, build_scratch, update_scratch = build_sizes(self.device, self._info, capacity)
        parts = Owned(self.device)
        try:
            structure = parts.add(Structure(self.device, self.level, size))
            scratch = parts.add(Scratch(self.device, max(build_scratch, update_scratch)))
        except BaseException:
            parts.destroy()
            raise
        self.destroy()
        self._parts = parts
        self.structure, self.scratch, self.capacity, self.built_count = structure, scratch, capacity, -1
        self._info.scratchData.deviceAddress = scratch.address
        return True

    @property
    def handle(self) -> Any:
        assert self.structure is not None
        return self.structure.handle

    def record(self, cb: Any, instances_address: int, count: int, update: bool = False) -> bool:
        """Record the build over `count` rows at `instances_address` (16-byte aligned), between
        barriers against ray-tracing shaders' reads; an update (refit) where `update` and the
        count is that of the last build. Returns whether it was an update."""
        if count > self.capacity:
            raise ValueError(f"{count} instances in a top level made for {self.capacity}: reserve() first")
        lib = self.device.vk.lib
        refit = bool(update) and count == self.built_count
        info = self._info
        info.mode = (
            lib.VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR
            if refit
            else lib.VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR
        )
        info.srcAccelerationStructure = self.handle if refit else self.device.vk.ffi.NULL
        info.dstAccelerationStructure = self.handle
        self._geometry.geometry.instances.data.deviceAddress = instances_address
        self._range[0].primitiveCount = count
        self._before.record(lib, cb)
        self.fns.build(cb, 1, info, self._ranges)
        self._after.record(lib, cb)
        self.built_count = count
        return refit

    def destroy(self) -> None:
        self._parts.destroy()
        self.structure = self.scratch = None
