"""Physical device choice, the logical device with its graphics queue, and one-shot submits."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..errors import UsageError
from .allocator import BlockAllocator
from .functions import instance_function
from .instance import Instance
from .pipeline_cache import PipelineCache
from .ray_tracing_support import RAY_TRACING_EXTENSIONS, ray_tracing_chain, ray_tracing_properties

# Preference order by VkPhysicalDeviceType: discrete, integrated, virtual, CPU, other.
_TYPE_RANK = {2: 0, 1: 1, 3: 2, 4: 3, 0: 4}
_TYPE_NAME = {0: "other", 1: "integrated GPU", 2: "discrete GPU", 3: "virtual GPU", 4: "CPU"}


@dataclass(frozen=True)
class DeviceInfo:
    name: str
    kind: str
    api_version: str
    driver_version: int
    vendor_id: int
    device_id: int
    driver_name: str
    driver_info: str
    timestamp_period_ns: float
    timestamp_valid_bits: int


class Device:
    """Picks a physical device (discrete, then integrated, then CPU; ECS_ENGINE_DEVICE=substring
    picks by name), creates the logical device and exposes the graphics queue."""

    def __init__(
        self, instance: Instance, surface: Any = None, prefer: str | None = None, extensions: tuple[str, ...] = ()
    ) -> None:
        vk = self.vk = instance.vk
        self.instance = instance
        prefer = prefer if prefer is not None else os.environ.get("ECS_ENGINE_DEVICE") or None
        physical = vk.vkEnumeratePhysicalDevices(instance.handle)
        if not physical:
            raise UsageError(
                "no Vulkan device found: install a driver, e.g. "
                "`sudo apt-get install -y mesa-vulkan-drivers` for the CPU driver (lavapipe)"
            )
        candidates = []
        for pd in physical:
            props = vk.vkGetPhysicalDeviceProperties(pd)
            family = self._graphics_family(pd, surface)
            if family is None or not _has_vulkan13(vk, pd, props):
                continue
            if prefer and prefer.lower() not in props.deviceName.lower():
                continue
            candidates.append((_TYPE_RANK.get(props.deviceType, 9), pd, props, family))
        if not candidates:
            names = [vk.vkGetPhysicalDeviceProperties(pd).deviceName for pd in physical]
            wanted = " with Vulkan 1.3 (dynamic rendering, synchronization2) and a graphics queue"
            wanted = f" matching ECS_ENGINE_DEVICE={prefer!r}" if prefer else wanted
            raise UsageError(f"no Vulkan device{wanted}; devices present: {', '.join(names)}")
        candidates.sort(key=lambda c: c[0])
        _, self.physical, props, self.queue_family = candidates[0]
        self.properties = props
        self.limits = props.limits
        self.memory_properties = vk.vkGetPhysicalDeviceMemoryProperties(self.physical)

        supported = {e.extensionName for e in vk.vkEnumerateDeviceExtensionProperties(self.physical, None)}
        exts = list(extensions) + (["VK_KHR_swapchain"] if surface is not None else [])
        missing = [e for e in exts if e not in supported]
        if missing:
            raise UsageError(f"{props.deviceName} lacks device extension(s) {missing}")

        f12 = vk.VkPhysicalDeviceVulkan12Features()
        f11 = vk.VkPhysicalDeviceVulkan11Features(pNext=f12)
        vk.vkGetPhysicalDeviceFeatures2(self.physical, vk.VkPhysicalDeviceFeatures2(pNext=f11))
        if not f11.shaderDrawParameters:  # the vertex shaders find a skinned vertex by gl_BaseVertex
            raise UsageError(f"{props.deviceName} lacks shaderDrawParameters (Vulkan 1.1), which the mesh shaders use")
        # ray tracing (gpu/acceleration.py): enabled where the device has all of it
        ray_chain = ray_tracing_chain(vk, self.physical, supported, f12)  # kept until the device is made
        if ray_chain is not None:
            exts += [e for e in RAY_TRACING_EXTENSIONS if e not in exts]
        # the frame graph records with dynamic rendering and emits synchronization2 barriers
        want13 = vk.VkPhysicalDeviceVulkan13Features(
            pNext=ray_chain[0] if ray_chain is not None else None, dynamicRendering=1, synchronization2=1
        )
        want12 = vk.VkPhysicalDeviceVulkan12Features(
            pNext=want13,
            drawIndirectCount=f12.drawIndirectCount,
            hostQueryReset=f12.hostQueryReset,
            bufferDeviceAddress=1 if ray_chain is not None else 0,
        )
        want11 = vk.VkPhysicalDeviceVulkan11Features(pNext=want12, shaderDrawParameters=1)
        self.features = {"drawIndirectCount": bool(f12.drawIndirectCount), "hostQueryReset": bool(f12.hostQueryReset)}
        self.features["rayTracing"] = ray_chain is not None
        self.ray_tracing = ray_tracing_properties(vk, self.physical) if ray_chain is not None else None
        base = vk.vkGetPhysicalDeviceFeatures(self.physical)
        # the indirect render mode needs all three (checked there, with one message if one lacks)
        # anisotropic texture filtering and wireframe/point fill where the device has them;
        # independent blending for weighted transparency's two targets (render/passes/oit.py); storage
        # images of r16f and the like (the SSAO passes' ao image: render/post/ssao_passes.py)
        optional = (
            "multiDrawIndirect",
            "drawIndirectFirstInstance",
            "samplerAnisotropy",
            "fillModeNonSolid",
            "independentBlend",
            "shaderStorageImageExtendedFormats",
        )
        features = vk.VkPhysicalDeviceFeatures(**{name: getattr(base, name) for name in optional})
        self.features.update({name: bool(getattr(base, name)) for name in optional})
        # clustered lights walk their lists once per subgroup (subgroupMin/Max/Or in fragments)
        sub = vk.VkPhysicalDeviceSubgroupProperties()
        vk.vkGetPhysicalDeviceProperties2(self.physical, vk.VkPhysicalDeviceProperties2(pNext=sub))
        self.features["fragmentSubgroupArithmetic"] = bool(
            sub.supportedStages & vk.VK_SHADER_STAGE_FRAGMENT_BIT
            and sub.supportedOperations & vk.VK_SUBGROUP_FEATURE_ARITHMETIC_BIT
        )
        # Keep nested structs in locals until the call: the binding copies a list of structs into
        # an array, and what an element points to (here its priorities) lives only as long as
        # the Python object of that element.
        queue_info = vk.VkDeviceQueueCreateInfo(queueFamilyIndex=self.queue_family, pQueuePriorities=[1.0])
        info = vk.VkDeviceCreateInfo(
            pNext=want11,
            pQueueCreateInfos=[queue_info],
            ppEnabledExtensionNames=exts,
            pEnabledFeatures=features,
        )
        self.handle = vk.vkCreateDevice(self.physical, info, None)
        self.queue = vk.vkGetDeviceQueue(self.handle, self.queue_family, 0)
        self._pool = vk.vkCreateCommandPool(
            self.handle,
            vk.VkCommandPoolCreateInfo(
                flags=vk.VK_COMMAND_POOL_CREATE_TRANSIENT_BIT, queueFamilyIndex=self.queue_family
            ),
            None,
        )
        self.info = self._describe(props)
        self.allocator = BlockAllocator(vk, self.handle, self.memory_properties, props.deviceName)
        self._pipeline_cache: PipelineCache | None = None
        # bumped when a buffer, image, framebuffer or pipeline is made, a buffer, image or
        # descriptor pool destroyed, a descriptor set written or secondaries' pools destroyed: a
        # command buffer kept to be submitted again (render/frame/replay.py) is valid while it stays
        self.objects_version = 0

    @property
    def pipeline_cache(self) -> PipelineCache:
        """The one pipeline cache of this device, made on first use, saved when it is destroyed."""
        if self._pipeline_cache is None:
            self._pipeline_cache = PipelineCache(self.vk, self.handle, self.info)
        return self._pipeline_cache

    def _graphics_family(self, pd: Any, surface: Any) -> int | None:
        vk = self.vk
        for i, q in enumerate(vk.vkGetPhysicalDeviceQueueFamilyProperties(pd)):
            if not q.queueFlags & vk.VK_QUEUE_GRAPHICS_BIT:
                continue
            if surface is not None:
                present = instance_function(self.instance, "vkGetPhysicalDeviceSurfaceSupportKHR")(pd, i, surface)
                if not present:
                    continue
            return i
        return None

    def _describe(self, props: Any) -> DeviceInfo:
        vk = self.vk
        driver = vk.VkPhysicalDeviceDriverProperties()
        vk.vkGetPhysicalDeviceProperties2(self.physical, vk.VkPhysicalDeviceProperties2(pNext=driver))
        families = vk.vkGetPhysicalDeviceQueueFamilyProperties(self.physical)
        v = props.apiVersion
        return DeviceInfo(
            name=props.deviceName,
            kind=_TYPE_NAME.get(props.deviceType, "other"),
            api_version=f"{vk.VK_VERSION_MAJOR(v)}.{vk.VK_VERSION_MINOR(v)}.{vk.VK_VERSION_PATCH(v)}",
            driver_version=props.driverVersion,
            vendor_id=props.vendorID,
            device_id=props.deviceID,
            driver_name=_text(vk, driver.driverName),
            driver_info=_text(vk, driver.driverInfo),
            timestamp_period_ns=float(props.limits.timestampPeriod),
            timestamp_valid_bits=int(families[self.queue_family].timestampValidBits),
        )

    def submit_once(self, record: Callable[[Any], None]) -> None:
        """Record with `record(command_buffer)`, submit, and wait (uploads, readbacks)."""
        vk = self.vk
        cb = vk.vkAllocateCommandBuffers(
            self.handle,
            vk.VkCommandBufferAllocateInfo(
                commandPool=self._pool, level=vk.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1
            ),
        )[0]
        fence = vk.vkCreateFence(self.handle, vk.VkFenceCreateInfo(), None)
        try:
            vk.vkBeginCommandBuffer(
                cb, vk.VkCommandBufferBeginInfo(flags=vk.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT)
            )
            record(cb)
            vk.vkEndCommandBuffer(cb)
            vk.vkQueueSubmit(self.queue, 1, [vk.VkSubmitInfo(pCommandBuffers=[cb])], fence)
            vk.vkWaitForFences(self.handle, 1, [fence], vk.VK_TRUE, 2**64 - 1)
        finally:
            vk.vkDestroyFence(self.handle, fence, None)
            vk.vkFreeCommandBuffers(self.handle, self._pool, 1, [cb])

    def wait_idle(self) -> None:
        self.vk.vkDeviceWaitIdle(self.handle)

    def destroy(self) -> None:
        if self.handle is None:
            return
        vk = self.vk
        vk.vkDeviceWaitIdle(self.handle)
        if self._pipeline_cache is not None:
            self._pipeline_cache.destroy()
        self.allocator.destroy()
        vk.vkDestroyCommandPool(self.handle, self._pool, None)
        vk.vkDestroyDevice(self.handle, None)
        self.handle = None


def _has_vulkan13(vk: Any, physical: Any, props: Any) -> bool:
    """Vulkan 1.3 with dynamic rendering and synchronization2 (required in 1.3, checked anyway:
    a driver that reports 1.3 without them would fail later with a less clear message)."""
    if vk.VK_VERSION_MAJOR(props.apiVersion) == 1 and vk.VK_VERSION_MINOR(props.apiVersion) < 3:
        return False
    f13 = vk.VkPhysicalDeviceVulkan13Features()
    vk.vkGetPhysicalDeviceFeatures2(physical, vk.VkPhysicalDeviceFeatures2(pNext=f13))
    return bool(f13.dynamicRendering and f13.synchronization2)


def _text(vk: Any, value: Any) -> str:
    if isinstance(value, str):
        return value
    try:
        return vk.ffi.string(value).decode(errors="replace")
    except TypeError:
        return str(value)
