"""One acceleration structure (VK_KHR_acceleration_structure) and what every build needs: the
extension's entry points of a device, a structure in its own device-local buffer with its device
address, a scratch buffer at the device's alignment, a build's geometry info and the sizes it
needs. Apart from acceleration.py, which builds the bottom levels of meshes and the top level of
a frame from these, so that each stays a readable size; acceleration.py re-exports these names.

Every call is a raw cffi call with structs made by `ffi.new`: the `vulkan` binding's wrappers of
these functions return their info struct instead of an address, and some of its ray-tracing
constants are wrong (the `vk.lib` values are right), so these modules read constants from
`vk.lib`. The GPU host's driver builds on the device only (no host builds).
"""

from __future__ import annotations

from typing import Any

from .frames import check
from .functions import raw_device_function
from .memory import DEVICE, Buffer
from .owned import Owned

_FUNCTIONS = {
    "create": "vkCreateAccelerationStructureKHR",
    "destroy": "vkDestroyAccelerationStructureKHR",
    "sizes": "vkGetAccelerationStructureBuildSizesKHR",
    "build": "vkCmdBuildAccelerationStructuresKHR",
    "address": "vkGetAccelerationStructureDeviceAddressKHR",
    "write_properties": "vkCmdWriteAccelerationStructuresPropertiesKHR",
    "copy": "vkCmdCopyAccelerationStructureKHR",
}


class AccelerationFunctions:
    """The extension's entry points of one device, typed cffi pointers."""

    create: Any
    destroy: Any
    sizes: Any
    build: Any
    address: Any
    write_properties: Any
    copy: Any

    def __init__(self, device: Any) -> None:
        if device.ray_tracing is None:
            raise RuntimeError(f"{device.info.name} has no ray tracing (VK_KHR_acceleration_structure)")
        for attr, name in _FUNCTIONS.items():
            setattr(self, attr, raw_device_function(device, name))


def functions(device: Any) -> AccelerationFunctions:
    """The device's AccelerationFunctions, made once."""
    made = getattr(device, "_acceleration_functions", None)
    if made is None:
        made = device._acceleration_functions = AccelerationFunctions(device)
    return made


def _usage(vk: Any, extra: int) -> int:
    return extra | vk.lib.VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT


def ray_input_usage(device: Any) -> int:
    """Usage bits a vertex, index or instance buffer needs to feed a build (0 without ray tracing)."""
    if device.ray_tracing is None:
        return 0
    lib = device.vk.lib
    return (
        lib.VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT
        | lib.VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR
    )


class Structure:
    """One VkAccelerationStructureKHR in its own device-local buffer, and its device address."""

    def __init__(self, device: Any, level: int, size: int) -> None:
        vk, lib, ffi = device.vk, device.vk.lib, device.vk.ffi
        self.device = device
        self.level = level
        self.size = int(size)
        self.owned = Owned(device)  # the buffer, then the structure in it (destroyed first)
        usage = _usage(vk, lib.VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR)
        self.buffer = self.owned.add(Buffer(device, self.size, usage, DEVICE))
        fns = functions(device)
        info = ffi.new(
            "VkAccelerationStructureCreateInfoKHR*",
            {
                "sType": lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR,
                "buffer": self.buffer.handle,
                "size": self.size,
                "type": level,
            },
        )
        out = ffi.new("VkAccelerationStructureKHR*")
        try:
            check(vk, fns.create(device.handle, info, ffi.NULL, out))
        except BaseException:
            self.owned.destroy()
            raise
        handle = self.handle = out[0]
        self.owned.add(handle, lambda: fns.destroy(device.handle, handle, ffi.NULL))
        where = ffi.new(
            "VkAccelerationStructureDeviceAddressInfoKHR*",
            {
                "sType": lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                "accelerationStructure": self.handle,
            },
        )
        self.address = int(fns.address(device.handle, where))

    def destroy(self) -> None:
        self.owned.destroy()
        self.handle = None


class Scratch:
    """A device-local scratch buffer whose address is rounded up to the device's alignment."""

    def __init__(self, device: Any, size: int) -> None:
        vk = device.vk
        align = device.ray_tracing.scratch_alignment
        self.size = int(size)
        self.buffer = Buffer(device, self.size + align, _usage(vk, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT), DEVICE)
        self.address = -(-self.buffer.address // align) * align

    def destroy(self) -> None:
        self.buffer.destroy()


def build_info(device: Any, ffi: Any, level: int, flags: int, geometry: Any) -> Any:
    lib = device.vk.lib
    info = ffi.new("VkAccelerationStructureBuildGeometryInfoKHR*")
    info.sType = lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR
    info.type = level
    info.flags = flags
    info.mode = lib.VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR
    info.geometryCount = 1
    info.pGeometries = geometry
    return info


def build_sizes(device: Any, info: Any, primitives: int) -> tuple[int, int, int]:
    """(structure bytes, build scratch bytes, update scratch bytes) for `primitives` at most."""
    lib, ffi = device.vk.lib, device.vk.ffi
    sizes = ffi.new(
        "VkAccelerationStructureBuildSizesInfoKHR*",
        {"sType": lib.VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR},
    )
    counts = ffi.new("uint32_t[1]", [primitives])
    functions(device).sizes(device.handle, lib.VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, info, counts, sizes)
    return int(sizes.accelerationStructureSize), int(sizes.buildScratchSize), int(sizes.updateScratchSize)
