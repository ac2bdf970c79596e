"""The device's VkPipelineCache, loaded from and saved to ~/.cache/ecs_engine (user_dirs.cache_home).

One per device (Device.pipeline_cache), shared by every pipeline made on it: two caches on one
file would each save what they saw, and the last one destroyed would overwrite the other's.
"""

from __future__ import annotations

import os
from typing import Any

from ..user_dirs import cache_home


class PipelineCache:
    """VkPipelineCache loaded from and saved to ~/.cache/ecs_engine, one file per device and
    driver (the driver rejects a foreign cache itself, but one file each keeps them useful)."""

    def __init__(self, vk: Any, device_handle: Any, info: Any) -> None:
        self.vk = vk
        self.device_handle = device_handle
        base = cache_home() / "ecs_engine"
        self.path = base / f"pipelines-{info.vendor_id:04x}-{info.device_id:04x}-{info.driver_version:08x}.bin"
        data = b""
        try:
            data = self.path.read_bytes()
        except OSError:
            pass
        if data:
            self.handle = vk.vkCreatePipelineCache(
                device_handle,
                vk.VkPipelineCacheCreateInfo(initialDataSize=len(data), pInitialData=vk.ffi.from_buffer(data)),
                None,
            )
        else:
            self.handle = vk.vkCreatePipelineCache(device_handle, vk.VkPipelineCacheCreateInfo(), None)

    def save(self) -> None:
        vk = self.vk
        size = vk.ffi.new("size_t*")  # the binding has no wrapper for this call: use the raw one
        if vk.lib.vkGetPipelineCacheData(self.device_handle, self.handle, size, vk.ffi.NULL) != vk.VK_SUCCESS:
            return
        buf = vk.ffi.new("char[]", size[0])
        if vk.lib.vkGetPipelineCacheData(self.device_handle, self.handle, size, buf) != vk.VK_SUCCESS:
            return
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_bytes(bytes(vk.ffi.buffer(buf, size[0])))
            os.replace(tmp, self.path)
        except OSError:
            pass  # a cache that cannot be written only costs start-up time

    def destroy(self) -> None:
        if self.handle is not None:
            self.save()
            self.vk.vkDestroyPipelineCache(self.device_handle, self.handle, None)
            self.handle = None
