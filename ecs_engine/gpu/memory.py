"""Buffers (host-mapped as NumPy arrays, or device-local with staging uploads) and images, in
memory from the device's block allocator (allocator.py).

A host buffer's `array()` is an `np.frombuffer` view straight into GPU-visible memory, so a job
writes instance rows where the GPU reads them. Per-frame buffers grow by doubling (`grown`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .allocator import ADDRESSED, DEVICE, HOST, UPLOAD
from .device import Device
from .owned import Owned

__all__ = ["DEVICE", "HOST", "UPLOAD", "Buffer", "Image", "upload"]


class Buffer:
    """A VkBuffer in a suballocation. HOST buffers are mapped; `array()` views their bytes."""

    def __init__(self, device: Device, size: int, usage: int, where: str = HOST) -> None:
        vk = device.vk
        self.device = device
        self.size = int(size)
        self.usage = usage
        self.where = where
        self._views: dict[tuple[Any, Any, int], np.ndarray] = {}  # array()'s, made once each
        if where == DEVICE:
            usage |= vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
        device.objects_version += 1
        self.handle = vk.vkCreateBuffer(
            device.handle,
            vk.VkBufferCreateInfo(size=max(self.size, 4), usage=usage, sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE),
            None,
        )
        req = vk.vkGetBufferMemoryRequirements(device.handle, self.handle)
        addressed = bool(usage & vk.lib.VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT)
        self.allocation = device.allocator.allocate(req, where, ADDRESSED if addressed else "buffer")
        vk.vkBindBufferMemory(device.handle, self.handle, self.allocation.memory, self.allocation.offset)

    def bytes(self) -> np.ndarray:
        if self.where == DEVICE:
            raise ValueError("only host and upload buffers are mapped")
        start = self.allocation.offset
        block = self.allocation.block
        if block.view is None:
            block.view = np.frombuffer(block.mapped, dtype=np.uint8)
        return block.view[start : start + self.size]

    def array(self, dtype: Any, shape: tuple[int, ...] | int | None = None, offset: int = 0) -> np.ndarray:
        """A NumPy view of the mapped bytes (writes go straight to memory the GPU reads). The
        views are kept per (dtype, shape, offset): the mapping of a buffer never moves, and a
        frame asks for the same ones each time (making one is ~3 us of NumPy calls)."""
        key = (dtype, tuple(shape) if isinstance(shape, list) else shape, offset)
        views = self._views
        found = views.get(key)
        if found is not None:
            return found
        if len(views) >= 16:  # shapes that follow a count (lights, materials) come and go
            views.clear()
        made = views[key] = self._array(dtype, shape, offset)
        return made

    def _array(self, dtype: Any, shape: tuple[int, ...] | int | None, offset: int) -> np.ndarray:
        raw = self.bytes()[offset:]
        dt = np.dtype(dtype)
        if shape is None:
            return raw[: len(raw) // dt.itemsize * dt.itemsize].view(dt)
        shape = (shape,) if isinstance(shape, int) else shape
        count = math.prod(shape) * dt.itemsize
        return raw[:count].view(dt).reshape(shape)

    @property
    def address(self) -> int:
        """The buffer's device address (usage SHADER_DEVICE_ADDRESS; the raw call: the binding's
        wrapper returns its argument instead)."""
        vk = self.device.vk
        info = vk.VkBufferDeviceAddressInfo(buffer=self.handle)
        return int(vk.lib.vkGetBufferDeviceAddress(self.device.handle, vk.ffi.addressof(info)))

    def descriptor(self, offset: int = 0, size: int | None = None) -> Any:
        vk = self.device.vk
        return vk.VkDescriptorBufferInfo(buffer=self.handle, offset=offset, range=size or self.size)

    def grown(self, needed: int, owned: Owned | None = None) -> Buffer:
        """This buffer while it holds `needed` bytes; else a new one of the same usage and at
        least twice the size, and this one is destroyed (released from `owned`, the scope that
        owns it, where given; the new one is then owned there in its place). Call it only when
        the GPU no longer reads this buffer (a frame slot whose fence was waited on), and
        rewrite the descriptors that named it (the handle changes)."""
        if needed <= self.size:
            return self
        bigger = Buffer(self.device, max(needed, 2 * self.size), self.usage, self.where)  # may fail: keep this one
        if owned is None:
            self.destroy()
        else:
            owned.release(self)
            owned.add(bigger)
        return bigger

    def destroy(self) -> None:
        if self.handle is None:
            return
        self.device.objects_version += 1
        self.device.vk.vkDestroyBuffer(self.device.handle, self.handle, None)
        self.device.allocator.free(self.allocation)
        self._views.clear()  # they would see whatever is allocated there next
        self.handle = None


def upload(device: Device, data: np.ndarray, usage: int) -> Buffer:
    """A device-local buffer holding `data`, copied through a temporary staging buffer."""
    vk = device.vk
    raw = np.ascontiguousarray(data).view(np.uint8).reshape(-1)
    target = Buffer(device, raw.nbytes, usage, DEVICE)
    if not raw.nbytes:  # an empty mesh: a buffer to bind, nothing to copy (a zero-size copy is invalid)
        return target
    staging = Buffer(device, raw.nbytes, vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, HOST)
    try:
        staging.bytes()[:] = raw
        region = vk.VkBufferCopy(srcOffset=0, dstOffset=0, size=raw.nbytes)
        device.submit_once(lambda cb: vk.vkCmdCopyBuffer(cb, staging.handle, target.handle, 1, [region]))
    finally:
        staging.destroy()
    return target


class Image:
    """A 2D device-local image with one view (colour or depth attachments, readback source); with
    `layers`, an array of that many layers whose view is a 2D array (layer_view gives one layer)."""

    def __init__(
        self,
        device: Device,
        width: int,
        height: int,
        fmt: int,
        usage: int,
        aspect: int,
        samples: int = 1,
        layers: int | None = None,
    ) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height, self.format, self.aspect = width, height, fmt, aspect
        # the image, its memory and its view, destroyed view first; a failure half-way (out of
        # memory) leaves nothing behind
        self.owned = Owned(device)
        try:
            self.handle = self.owned.create(
                "Image",
                vk.VkImageCreateInfo(
                    imageType=vk.VK_IMAGE_TYPE_2D,
                    format=fmt,
                    extent=vk.VkExtent3D(width, height, 1),
                    mipLevels=1,
                    arrayLayers=layers or 1,
                    samples=samples,  # VkSampleCountFlagBits: the count itself
                    tiling=vk.VK_IMAGE_TILING_OPTIMAL,
                    usage=usage,
                    sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
                    initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
                ),
            )
            req = vk.vkGetImageMemoryRequirements(device.handle, self.handle)
            self.allocation = self.owned.allocation(device.allocator.allocate(req, DEVICE, "image"))
            vk.vkBindImageMemory(device.handle, self.handle, self.allocation.memory, self.allocation.offset)
            kind = vk.VK_IMAGE_VIEW_TYPE_2D if layers is None else vk.VK_IMAGE_VIEW_TYPE_2D_ARRAY
            self.view = self.owned.create("ImageView", self._view_info(kind, 0, layers or 1))
        except BaseException:
            self.owned.destroy()
            raise

    def _view_info(self, kind: int, first: int, count: int) -> Any:
        vk = self.device.vk
        return vk.VkImageViewCreateInfo(
            image=self.handle,
            viewType=kind,
            format=self.format,
            subresourceRange=vk.VkImageSubresourceRange(
                aspectMask=self.aspect, baseMipLevel=0, levelCount=1, baseArrayLayer=first, layerCount=count
            ),
        )

    def layer_view(self, layer: int) -> Any:
        """A 2D view of one layer (an attachment), for the caller to destroy before the image."""
        vk = self.device.vk
        return vk.vkCreateImageView(self.device.handle, self._view_info(vk.VK_IMAGE_VIEW_TYPE_2D, layer, 1), None)

    def destroy(self) -> None:
        self.owned.destroy()
        self.handle = None
