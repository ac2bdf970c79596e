"""Vulkan entry points by name, in the three forms the engine calls them.

- `instance_function` / `device_function`: the `vulkan` binding's wrappers for extension
  functions (structs and lists converted, VkResult errors raised), for set-up calls.
- `raw_device_function`: the cffi pointer, typed, for per-frame calls where the wrapper's
  microseconds matter or its exceptions get in the way (VK_SUBOPTIMAL_KHR is a success).
- `native_device_functions`: ctypes functions that numba-compiled loops can call (gpu/
  native_recorder.py), taking handles as signed 64-bit integers.
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterable
from typing import Any, Protocol


class Dispatchable(Protocol):
    """An Instance or a Device: the binding module and the Vulkan handle."""

    vk: Any
    handle: Any


_i64, _u32, _i32 = ctypes.c_int64, ctypes.c_uint32, ctypes.c_int32
# Handles and pointers travel as int64 (the C calling convention passes int64 and uint64 alike).
NATIVE_PROTOTYPES = {
    "vkCmdBindPipeline": ctypes.CFUNCTYPE(None, _i64, _u32, _i64),
    "vkCmdBindVertexBuffers": ctypes.CFUNCTYPE(None, _i64, _u32, _u32, _i64, _i64),
    "vkCmdBindIndexBuffer": ctypes.CFUNCTYPE(None, _i64, _i64, _i64, _u32),
    "vkCmdPushConstants": ctypes.CFUNCTYPE(None, _i64, _i64, _u32, _u32, _u32, _i64),
    "vkCmdDrawIndexed": ctypes.CFUNCTYPE(None, _i64, _u32, _u32, _u32, _i32, _u32),
    "vkBeginCommandBuffer": ctypes.CFUNCTYPE(_i32, _i64, _i64),
    "vkEndCommandBuffer": ctypes.CFUNCTYPE(_i32, _i64),
    "vkCmdSetViewport": ctypes.CFUNCTYPE(None, _i64, _u32, _u32, _i64),
    "vkCmdSetScissor": ctypes.CFUNCTYPE(None, _i64, _u32, _u32, _i64),
    "vkCmdBindDescriptorSets": ctypes.CFUNCTYPE(None, _i64, _u32, _i64, _u32, _u32, _i64, _u32, _i64),
}


def instance_function(instance: Dispatchable, name: str) -> Any:
    return instance.vk.vkGetInstanceProcAddr(instance.handle, name)


def device_function(device: Dispatchable, name: str) -> Any:
    return device.vk.vkGetDeviceProcAddr(device.handle, name)


def device_address(device: Dispatchable, name: str) -> Any:
    """The raw entry point (a cffi pointer); RuntimeError when the device has none."""
    vk = device.vk
    ptr = vk.lib.vkGetDeviceProcAddr(device.handle, name.encode())
    if ptr == vk.ffi.NULL:
        raise RuntimeError(f"{name} has no device entry point")
    return ptr


def raw_device_function(device: Dispatchable, name: str) -> Any:
    return device.vk.ffi.cast(f"PFN_{name}", device_address(device, name))


def handle_int(vk: Any, handle: Any) -> int:
    """A handle or pointer as a signed 64-bit value (same bits)."""
    value = int(vk.ffi.cast("uintptr_t", handle))
    return value - (1 << 64) if value >= 1 << 63 else value


def native_device_functions(device: Dispatchable, names: Iterable[str]) -> dict[str, Any]:
    """Typed ctypes functions (see NATIVE_PROTOTYPES) for numba-compiled loops."""
    return {name: NATIVE_PROTOTYPES[name](handle_int(device.vk, device_address(device, name))) for name in names}
