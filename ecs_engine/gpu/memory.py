"""Device memory: a block suballocator, buffers (host-mapped as NumPy arrays, or device-local
with staging uploads) and images.

Few `vkAllocateMemory` calls, many resources: blocks of BLOCK_SIZE per memory type (larger
requests get a block of their own), first-fit free lists with merging. Buffers and images use
separate blocks, so bufferImageGranularity never matters. Host-visible blocks are mapped once,
persistently; a buffer's `array()` is an `np.frombuffer` view straight into GPU-visible memory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import UsageError

if TYPE_CHECKING:
    from .device import Device

BLOCK_SIZE = 64 * 2**20
HOST = "host"  # HOST_VISIBLE | HOST_COHERENT, persistently mapped
DEVICE = "device"  # DEVICE_LOCAL


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
    def __init__(self, device: Device) -> None:
        self.device = device
        # keyed by (memory type, resource kind, where): a type can be both device-local and
        # host-visible (CPU drivers, resizable BAR), and only HOST blocks are mapped
        self._blocks: dict[tuple[int, str, str], list[_Block]] = {}
        self.allocate_calls = 0  # how many vkAllocateMemory calls were made

    def _memory_type(self, type_bits: int, where: str) -> int:
        vk = self.device.vk
        props = self.device.memory_properties
        if where == HOST:
            wanted = [vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | vk.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT]
        else:
            wanted = [vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0]
        for flags in wanted:
            for i in range(props.memoryTypeCount):
                if type_bits & (1 << i) and props.memoryTypes[i].propertyFlags & flags == flags:
                    return i
        raise UsageError(f"{self.device.info.name} has no {where} memory type for this resource")

    def allocate(self, requirements: Any, where: str, kind: str) -> Allocation:
        vk = self.device.vk
        type_index = self._memory_type(requirements.memoryTypeBits, where)
        blocks = self._blocks.setdefault((type_index, kind, where), [])
        size, alignment = int(requirements.size), int(requirements.alignment)
        for block in blocks:
            offset = block.take(size, alignment)
            if offset is not None:
                return Allocation(block, offset, size)
        block_size = max(BLOCK_SIZE, _align(size, 2**20))
        try:
            memory = vk.vkAllocateMemory(self.device.handle, vk.VkMemoryAllocateInfo(
                allocationSize=block_size, memoryTypeIndex=type_index), None)
        except (vk.VkErrorOutOfDeviceMemory, vk.VkErrorOutOfHostMemory) as exc:
            raise UsageError(f"out of GPU memory allocating {block_size / 2**20:.0f} MiB") from exc
        self.allocate_calls += 1
        mapped = vk.vkMapMemory(self.device.handle, memory, 0, block_size, 0) if where == HOST else None
        block = _Block(memory, block_size, mapped, [(0, block_size)])
        blocks.append(block)
        offset = block.take(size, alignment)
        assert offset is not None
        return Allocation(block, offset, size)

    def free(self, allocation: Allocation) -> None:
        allocation.block.give(allocation.offset, allocation.size)

    def stats(self) -> dict[str, int]:
        blocks = [b for bs in self._blocks.values() for b in bs]
        return {"blocks": len(blocks), "allocate_calls": self.allocate_calls,
                "reserved_bytes": sum(b.size for b in blocks), "used_bytes": sum(b.used for b in blocks)}

    def destroy(self) -> None:
        vk = self.device.vk
        for blocks in self._blocks.values():
            for block in blocks:
                if block.mapped is not None:
                    vk.vkUnmapMemory(self.device.handle, block.memory)
                vk.vkFreeMemory(self.device.handle, block.memory, None)
        self._blocks.clear()


class Buffer:
    """A VkBuffer in a suballocation. HOST buffers are mapped; `array()` views their bytes."""

    def __init__(self, device: Device, size: int, usage: int, where: str = HOST) -> None:
        vk = device.vk
        self.device = device
        self.size = int(size)
        self.where = where
        if where == DEVICE:
            usage |= vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
        self.handle = vk.vkCreateBuffer(device.handle, vk.VkBufferCreateInfo(
            size=max(self.size, 4), usage=usage, sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE), None)
        req = vk.vkGetBufferMemoryRequirements(device.handle, self.handle)
        self.allocation = device.allocator.allocate(req, where, "buffer")
        vk.vkBindBufferMemory(device.handle, self.handle, self.allocation.memory, self.allocation.offset)

    def bytes(self) -> np.ndarray:
        if self.where != HOST:
            raise ValueError("only host buffers are mapped")
        start = self.allocation.offset
        block = self.allocation.block
        if block.view is None:
            block.view = np.frombuffer(block.mapped, dtype=np.uint8)
        return block.view[start : start + self.size]

    def array(self, dtype: Any, shape: tuple[int, ...] | int | None = None, offset: int = 0) -> np.ndarray:
        """A NumPy view of the mapped bytes (writes go straight to memory the GPU reads)."""
        raw = self.bytes()[offset:]
        dt = np.dtype(dtype)
        if shape is None:
            return raw[: len(raw) // dt.itemsize * dt.itemsize].view(dt)
        shape = (shape,) if isinstance(shape, int) else shape
        count = math.prod(shape) * dt.itemsize
        return raw[:count].view(dt).reshape(shape)

    def descriptor(self, offset: int = 0, size: int | None = None) -> Any:
        vk = self.device.vk
        return vk.VkDescriptorBufferInfo(buffer=self.handle, offset=offset, range=size or self.size)

    def destroy(self) -> None:
        if self.handle is None:
            return
        self.device.vk.vkDestroyBuffer(self.device.handle, self.handle, None)
        self.device.allocator.free(self.allocation)
        self.handle = None


def upload(device: Device, data: np.ndarray, usage: int) -> Buffer:
    """A device-local buffer holding `data`, copied through a temporary staging buffer."""
    vk = device.vk
    raw = np.ascontiguousarray(data).view(np.uint8).reshape(-1)
    target = Buffer(device, raw.nbytes, usage, DEVICE)
    staging = Buffer(device, raw.nbytes, vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, HOST)
    try:
        staging.bytes()[:] = raw
        region = vk.VkBufferCopy(srcOffset=0, dstOffset=0, size=raw.nbytes)
        device.submit_once(lambda cb: vk.vkCmdCopyBuffer(cb, staging.handle, target.handle, 1, [region]))
    finally:
        staging.destroy()
    return target


class Image:
    """A 2D device-local image with one view (colour or depth attachments, readback source)."""

    def __init__(self, device: Device, width: int, height: int, fmt: int, usage: int, aspect: int) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height, self.format = width, height, fmt
        self.handle = vk.vkCreateImage(device.handle, vk.VkImageCreateInfo(
            imageType=vk.VK_IMAGE_TYPE_2D, format=fmt, extent=vk.VkExtent3D(width, height, 1),
            mipLevels=1, arrayLayers=1, samples=vk.VK_SAMPLE_COUNT_1_BIT, tiling=vk.VK_IMAGE_TILING_OPTIMAL,
            usage=usage, sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE, initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED), None)
        req = vk.vkGetImageMemoryRequirements(device.handle, self.handle)
        self.allocation = device.allocator.allocate(req, DEVICE, "image")
        vk.vkBindImageMemory(device.handle, self.handle, self.allocation.memory, self.allocation.offset)
        self.view = vk.vkCreateImageView(device.handle, vk.VkImageViewCreateInfo(
            image=self.handle, viewType=vk.VK_IMAGE_VIEW_TYPE_2D, format=fmt,
            subresourceRange=vk.VkImageSubresourceRange(aspectMask=aspect, baseMipLevel=0, levelCount=1,
                                                        baseArrayLayer=0, layerCount=1)), None)

    def destroy(self) -> None:
        if self.handle is None:
            return
        vk = self.device.vk
        vk.vkDestroyImageView(self.device.handle, self.view, None)
        vk.vkDestroyImage(self.device.handle, self.handle, None)
        self.device.allocator.free(self.allocation)
        self.handle = None
