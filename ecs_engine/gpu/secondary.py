"""Secondary command buffers for worker threads: per frame in flight and per thread, one command
pool (Vulkan pools are not thread-safe) that is reset whole when the frame slot comes round,
unless the slot's frame is replayed (render/frame/replay.py): then what it recorded stays."""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, Any

from .frames import check

if TYPE_CHECKING:
    from .device import Device
    from .pipeline import AttachmentFormats


class _ThreadPool:
    def __init__(self, device: Device) -> None:
        vk = device.vk
        self.handle = vk.vkCreateCommandPool(
            device.handle,
            vk.VkCommandPoolCreateInfo(
                flags=vk.VK_COMMAND_POOL_CREATE_TRANSIENT_BIT, queueFamilyIndex=device.queue_family
            ),
            None,
        )
        self.buffers: list[Any] = []
        self.used = 0

    def destroy(self, device: Device) -> None:
        """The pool and its buffers (after the device is done with them)."""
        device.vk.vkDestroyCommandPool(device.handle, self.handle, None)


class SecondaryBuffers:
    def __init__(self, device: Device, frames: int) -> None:
        self.device = device
        self._pools: list[dict[int, _ThreadPool]] = [{} for _ in range(frames)]
        self._lock = threading.Lock()  # only guards the dict when a new thread shows up
        # per AttachmentFormats: the begin info of secondaries drawn with dynamic rendering and
        # what its pointers point to (the jobs begin them on worker threads, any time later)
        self._rendering_begins: dict[AttachmentFormats, tuple[Any, Any]] = {}

    def reset(self, frame: int) -> None:
        """Main thread, after the frame's fence: every buffer of that slot may be re-recorded."""
        lib = self.device.vk.lib
        for pool in self._pools[frame].values():
            if pool.used:
                check(self.device.vk, lib.vkResetCommandPool(self.device.handle, pool.handle, 0))
                pool.used = 0

    def acquire(self, frame: int) -> Any:
        """An unused secondary buffer from the calling thread's pool for this frame slot."""
        vk = self.device.vk
        pools = self._pools[frame]
        key = threading.get_ident()
        pool = pools.get(key)
        if pool is None:
            with self._lock:
                pool = pools[key] = _ThreadPool(self.device)
        if pool.used == len(pool.buffers):
            pool.buffers.append(
                vk.vkAllocateCommandBuffers(
                    self.device.handle,
                    vk.VkCommandBufferAllocateInfo(
                        commandPool=pool.handle, level=vk.VK_COMMAND_BUFFER_LEVEL_SECONDARY, commandBufferCount=1
                    ),
                )[0]
            )
        cb = pool.buffers[pool.used]
        pool.used += 1
        return cb

    def begin(self, frame: int, begin_info: Any) -> Any:
        """`acquire`, then begin it with `begin_info` (see `begin_info_rendering`); a raw call,
        as in gpu/frames.py."""
        vk = self.device.vk
        cb = self.acquire(frame)
        check(vk, vk.lib.vkBeginCommandBuffer(cb, vk.ffi.addressof(begin_info)))
        return cb

    def begin_info_rendering(self, formats: AttachmentFormats) -> Any:
        """Begin info for secondaries executed inside a vkCmdBeginRendering (begun with
        VK_RENDERING_CONTENTS_SECONDARY_COMMAND_BUFFERS_BIT) over attachments of `formats`: no
        render pass or framebuffer, the formats inherited instead. One per formats, kept for the
        life of these buffers (equal formats share it); not one-time: a frame recorded the same
        way again executes them again (render/frame/replay.py)."""
        kept = self._rendering_begins.get(formats)
        if kept is not None:
            return kept[0]
        vk = self.device.vk
        ffi = vk.ffi
        colors = ffi.new("VkFormat[]", list(formats.colors) or [0])
        rendering = ffi.new(
            "VkCommandBufferInheritanceRenderingInfo*",
            {
                "sType": vk.VK_STRUCTURE_TYPE_COMMAND_BUFFER_INHERITANCE_RENDERING_INFO,
                "colorAttachmentCount": len(formats.colors),
                "pColorAttachmentFormats": colors if formats.colors else ffi.NULL,
                "depthAttachmentFormat": formats.depth,
                "rasterizationSamples": formats.samples,
            },
        )
        inheritance = ffi.new(
            "VkCommandBufferInheritanceInfo*",
            {"sType": vk.VK_STRUCTURE_TYPE_COMMAND_BUFFER_INHERITANCE_INFO, "pNext": rendering},
        )
        begin = ffi.new(
            "VkCommandBufferBeginInfo*",
            {
                "sType": vk.VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                "flags": vk.VK_COMMAND_BUFFER_USAGE_RENDER_PASS_CONTINUE_BIT,
                "pInheritanceInfo": inheritance,
            },
        )
        with self._lock:  # (the main thread makes them; a lock costs nothing here)
            self._rendering_begins[formats] = (begin[0], (begin, inheritance, rendering, colors))
        return begin[0]

    def keep_threads(self, alive: set[int]) -> None:
        """Destroy the pools of threads that are gone (a resized worker pool); the device must be
        idle: their buffers may belong to frames in flight."""
        self.device.objects_version += 1  # what they recorded may not be submitted again
        for pools in self._pools:
            for ident in [k for k in pools if k not in alive]:
                pools.pop(ident).destroy(self.device)

    def pool_count(self) -> int:
        return sum(len(pools) for pools in self._pools)

    def destroy(self) -> None:
        for pools in self._pools:
            for pool in pools.values():
                pool.destroy(self.device)
        self._pools = []


def end_command_buffer(vk: Any, cb: Any) -> None:
    check(vk, vk.lib.vkEndCommandBuffer(cb))
