"""Whether a device can trace rays (VK_KHR_acceleration_structure and VK_KHR_ray_tracing_pipeline
with buffer device addresses), the feature structs that enable it, and its properties.

Ray queries are not needed (the NVIDIA driver of the GPU host lacks them): shadow rays are
traced from a ray-generation shader. `ECS_ENGINE_RAY_TRACING=0` leaves ray tracing off on a
device that has it (to try the refusal path, or to save the extensions' cost).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

RAY_TRACING_EXTENSIONS = (
    "VK_KHR_acceleration_structure",
    "VK_KHR_ray_tracing_pipeline",
    "VK_KHR_deferred_host_operations",  # required by VK_KHR_acceleration_structure
)


@dataclass(frozen=True)
class RayTracingProperties:
    handle_size: int  # shader group handle bytes
    handle_alignment: int  # of a record in the shader binding table
    base_alignment: int  # of each region's start
    max_recursion: int
    scratch_alignment: int  # of a build's scratch address


def ray_tracing_chain(vk: Any, physical: Any, supported: set[str], f12: Any) -> tuple[Any, ...] | None:
    """The feature structs to chain to the device's Vulkan 1.3 features, head first (keep the
    tuple alive until the device is made: the head's pNext names the others); None where
    something is missing or ECS_ENGINE_RAY_TRACING=0. Only queried where the extensions exist: the validation layer
    names structs of extensions a device lacks."""
    if os.environ.get("ECS_ENGINE_RAY_TRACING", "1") == "0":
        return None
    if any(e not in supported for e in RAY_TRACING_EXTENSIONS) or not f12.bufferDeviceAddress:
        return None
    pipeline = vk.VkPhysicalDeviceRayTracingPipelineFeaturesKHR(
        sType=vk.lib.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR
    )
    structures = vk.VkPhysicalDeviceAccelerationStructureFeaturesKHR(pNext=pipeline)
    vk.vkGetPhysicalDeviceFeatures2(physical, vk.VkPhysicalDeviceFeatures2(pNext=structures))
    if not (structures.accelerationStructure and pipeline.rayTracingPipeline):
        return None
    want_pipeline = vk.VkPhysicalDeviceRayTracingPipelineFeaturesKHR(
        sType=vk.lib.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR, rayTracingPipeline=1
    )
    return vk.VkPhysicalDeviceAccelerationStructureFeaturesKHR(
        pNext=want_pipeline, accelerationStructure=1
    ), want_pipeline


def ray_tracing_properties(vk: Any, physical: Any) -> RayTracingProperties:
    pipeline = vk.VkPhysicalDeviceRayTracingPipelinePropertiesKHR(
        sType=vk.lib.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_PROPERTIES_KHR
    )
    structures = vk.VkPhysicalDeviceAccelerationStructurePropertiesKHR(pNext=pipeline)
    vk.vkGetPhysicalDeviceProperties2(physical, vk.VkPhysicalDeviceProperties2(pNext=structures))
    return RayTracingProperties(
        handle_size=int(pipeline.shaderGroupHandleSize),
        handle_alignment=int(pipeline.shaderGroupHandleAlignment),
        base_alignment=int(pipeline.shaderGroupBaseAlignment),
        max_recursion=int(pipeline.maxRayRecursionDepth),
        scratch_alignment=int(structures.minAccelerationStructureScratchOffsetAlignment),
    )
