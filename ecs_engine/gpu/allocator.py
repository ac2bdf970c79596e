"""Device memory as a block suballocator: few `vkAllocateMemory` calls, many resources.

Blocks of BLOCK_SIZE per memory type (larger requests get a block of their own), first-fit free
lists with merging. Buffers and images use separate blocks, so bufferImageGranularity never
matters. Host-visible blocks are mapped once, persistently (see memory.Buffer.array).

The allocator knows the device only by its handle and memory properties, so device.py can own
one without memory.py (whose buffers and images take a Device) importing device.py back.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import UsageError

BLOCK_SIZE = 64 * 2**20
HOST = "host"  # HOST_VISIBLE | HOST_COHERENT, persistently mapped
DEVICE = "device"  # DEVICE_LOCAL
# DEVICE_LOCAL | HOST_VISIBLE | HOST_COHERENT where the device has it (resizable BAR: the GPU
# reads at its own memory's speed, the CPU writes across the bus), else HOST; mapped
UPLOAD = "upload"
ADDRESSED = "addressed"  # the resource kind of buffers with SHADER_DEVICE_ADDRESS usage


def _align(x: int, a: int) -> int:
    return (x + a - 1) // a * a


@dataclass
class _Block:
    memory: Any
    size: int
    mapped: Any  # cffi buffer over the whole block, or None
    free: list[tuple[int, int]] = field(default_factory=list)  # (offset, size), sorted by offset
    view: np.ndarray | None = None  # uint8 view of `mapped`, made once (np.frombuffer costs us a call)

    def take(self, size: int, alignment: int) -> int | None:
        for i, (off, length) in enumerate(self.free):
            start = _align(off, alignment)
            end = start + size
            if end <= off + length:
                pieces = [(off, start - off), (end, off + length - end)]
                self.free[i : i + 1] = [p for p in pieces if p[1] > 0]
                return start
        return None

    def give(self, offset: int, size: int) -> None:
        self.free.append((offset, size))
        self.free.sort()
        merged: list[tuple[int, int]] = []
        for off, length in self.free:
            if merged and merged[-1][0] + merged[-1][1] == off:
                merged[-1] = (merged[-1][0], merged[-1][1] + length)
            else:
                merged.append((off, length))
        self.free = merged

    @property
    def used(self) -> int:
        return self.size - sum(length for _, length in self.free)


@dataclass
class Allocation:
    block: _Block
    offset: int
    size: int

    @property
    def memory(self) -> Any:
        return self.block.memory


class BlockAllocator:
    def __init__(self, vk: Any, device_handle: Any, memory_properties: Any, device_name: str) -> None:
        self.vk = vk
        self.device_handle = device_handle
        self.memory_properties = memory_properties
        self.device_name = device_name
        # keyed by (memory type, resource kind, where): a type can be both device-local and
        # host-visible (CPU drivers, resizable BAR), and only HOST blocks are mapped
        self._blocks: dict[tuple[int, str, str], list[_Block]] = {}
        self.allocate_calls = 0  # how many vkAllocateMemory calls were made

    def _memory_type(self, type_bits: int, where: str) -> int:
        vk = self.vk
        props = self.memory_properties
        host = vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | vk.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
        if where == HOST:
            wanted = [host]
        elif where == UPLOAD:
            wanted = [host | vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, host]
        else:
            wanted = [vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0]
        for flags in wanted:
            for i in range(props.memoryTypeCount):
                if type_bits & (1 << i) and props.memoryTypes[i].propertyFlags & flags == flags:
                    return i
        raise UsageError(f"{self.device_name} has no {where} memory type for this resource")

    def allocate(self, requirements: Any, where: str, kind: str) -> Allocation:
        """A suballocation; UPLOAD falls back to HOST when the bus-visible device memory is full
        (a GPU without resizable BAR has 256 MiB of it)."""
        if where == UPLOAD:
            try:
                return self._allocate(requirements, UPLOAD, kind)
            except UsageError:
                where = HOST
        return self._allocate(requirements, where, kind)

    def _allocate(self, requirements: Any, where: str, kind: str) -> Allocation:
        vk = self.vk
        type_index = self._memory_type(requirements.memoryTypeBits, where)
        blocks = self._blocks.setdefault((type_index, kind, where), [])
        size, alignment = int(requirements.size), int(requirements.alignment)
        for block in blocks:
            offset = block.take(size, alignment)
            if offset is not None:
                return Allocation(block, offset, size)
        block_size = max(BLOCK_SIZE, _align(size, 2**20))
        # buffers read by their device address (ray tracing's inputs) live in blocks allocated so
        flags = (
            vk.VkMemoryAllocateFlagsInfo(flags=vk.lib.VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT)
            if kind == ADDRESSED
            else None
        )
        try:
            memory = vk.vkAllocateMemory(
                self.device_handle,
                vk.VkMemoryAllocateInfo(pNext=flags, allocationSize=block_size, memoryTypeIndex=type_index),
                None,
            )
        except (vk.VkErrorOutOfDeviceMemory, vk.VkErrorOutOfHostMemory) as exc:
            raise UsageError(f"out of GPU memory allocating {block_size / 2**20:.0f} MiB") from exc
        self.allocate_calls += 1
        mapped = vk.vkMapMemory(self.device_handle, memory, 0, block_size, 0) if where != DEVICE else None
        block = _Block(memory, block_size, mapped, [(0, block_size)])
        blocks.append(block)
        offset = block.take(size, alignment)
        assert offset is not None
        return Allocation(block, offset, size)

    def free(self, allocation: Allocation) -> None:
        allocation.block.give(allocation.offset, allocation.size)

    def stats(self) -> dict[str, int]:
        blocks = [b for bs in self._blocks.values() for b in bs]
        return {
            "blocks": len(blocks),
            "allocate_calls": self.allocate_calls,
            "reserved_bytes": sum(b.size for b in blocks),
            "used_bytes": sum(b.used for b in blocks),
        }

    def destroy(self) -> None:
        vk = self.vk
        for blocks in self._blocks.values():
            for block in blocks:
                if block.mapped is not None:
                    vk.vkUnmapMemory(self.device_handle, block.memory)
                vk.vkFreeMemory(self.device_handle, block.memory, None)
        self._blocks.clear()
