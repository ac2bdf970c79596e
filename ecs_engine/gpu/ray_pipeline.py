"""A ray-tracing pipeline (VK_KHR_ray_tracing_pipeline) and its shader binding table: one
ray-generation shader, miss shaders and triangle hit groups (a closest-hit and an any-hit
shader, either absent), and the raw
vkCmdTraceRaysKHR call with the table's regions made once.

The binding's constructors of the pipeline and group create infos default to wrong sTypes, and
its VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR is wrong: the values come from `vk.lib`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .frames import check
from .functions import raw_device_function
from .memory import HOST, Buffer
from .owned import Owned
from .pipeline import shader_module, specialization

UNUSED = 0xFFFFFFFF  # VK_SHADER_UNUSED_KHR (None in the binding)


def _align(x: int, a: int) -> int:
    return -(-x // a) * a


class RayPipeline:
    """Shaders by compiled name: `raygen`, `misses` (miss index i is the i-th), `hits` (hit group
    i: a closest-hit shader's name, None for a group with no shader, or a pair (closest hit,
    any hit), either None). `constants`: uint specialisation constants of every stage,
    constant_id 0, 1, ..."""

    def __init__(
        self,
        device: Any,
        layout: Any,
        raygen: str,
        misses: Sequence[str],
        hits: Sequence[str | tuple[str | None, str | None] | None] = (),
        constants: tuple[int, ...] = (),
        recursion: int = 1,
    ) -> None:
        vk, lib, ffi = device.vk, device.vk.lib, device.vk.ffi
        props = device.ray_tracing
        if props is None:
            raise RuntimeError(f"{device.info.name} has no ray-tracing pipelines")
        self.device = device
        self.layout = layout
        self.owned = Owned(device)  # the pipeline, then its binding table
        pairs = [h if isinstance(h, tuple) else (h, None) for h in hits]
        names = [raygen, *misses]
        kinds = [lib.VK_SHADER_STAGE_RAYGEN_BIT_KHR] + [lib.VK_SHADER_STAGE_MISS_BIT_KHR] * len(misses)
        hit_kinds = (lib.VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR, lib.VK_SHADER_STAGE_ANY_HIT_BIT_KHR)
        for pair in pairs:
            for name, kind in zip(pair, hit_kinds):
                if name is not None:
                    names.append(name)
                    kinds.append(kind)
        modules: list[Any] = []
        try:
            for name in names:
                modules.append(shader_module(device, name))
            spec, _data = specialization(vk, constants)
            stages = ffi.new("VkPipelineShaderStageCreateInfo[]", len(names))
            entry = ffi.new("char[]", b"main")
            for i, (module, kind) in enumerate(zip(modules, kinds)):
                stages[i].sType = vk.VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO
                stages[i].stage = kind
                stages[i].module = module
                stages[i].pName = entry
                stages[i].pSpecializationInfo = ffi.addressof(spec) if constants else ffi.NULL
            groups = ffi.new("VkRayTracingShaderGroupCreateInfoKHR[]", 1 + len(misses) + len(hits))
            stage = 0
            for i in range(len(groups)):
                g = groups[i]
                g.sType = lib.VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR
                g.generalShader = g.closestHitShader = g.anyHitShader = g.intersectionShader = UNUSED
                if i <= len(misses):  # ray generation, then the misses
                    g.type = lib.VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR
                    g.generalShader = stage
                    stage += 1
                else:
                    g.type = lib.VK_RAY_TRACING_SHADER_GROUP_TYPE_TRIANGLES_HIT_GROUP_KHR
                    closest, any_hit = pairs[i - 1 - len(misses)]
                    if closest is not None:
                        g.closestHitShader = stage
                        stage += 1
                    if any_hit is not None:
                        g.anyHitShader = stage
                        stage += 1
            info = ffi.new("VkRayTracingPipelineCreateInfoKHR*")
            info.sType = lib.VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR
            info.stageCount = len(names)
            info.pStages = stages
            info.groupCount = len(groups)
            info.pGroups = groups
            info.maxPipelineRayRecursionDepth = min(recursion, props.max_recursion)
            info.layout = layout
            out = ffi.new("VkPipeline*")
            create = raw_device_function(device, "vkCreateRayTracingPipelinesKHR")
            device.objects_version += 1
            check(vk, create(device.handle, ffi.NULL, device.pipeline_cache.handle, 1, info, ffi.NULL, out))
            pipeline = self.handle = out[0]
            self.owned.add(pipeline, lambda: vk.vkDestroyPipeline(device.handle, pipeline, None))
        finally:
            for module in modules:
                vk.vkDestroyShaderModule(device.handle, module, None)
        try:
            self._make_table(len(groups), 1 + len(misses))
        except BaseException:
            self.owned.destroy()
            raise
        self._trace = raw_device_function(device, "vkCmdTraceRaysKHR")
        self.bind_point = lib.VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR

    def _make_table(self, group_count: int, general: int) -> None:
        """The shader binding table: ray generation, misses, hit groups, each region aligned to the
        base alignment, each record to the handle alignment."""
        device, lib, ffi = self.device, self.device.vk.lib, self.device.vk.ffi
        props = device.ray_tracing
        size = props.handle_size
        handles = ffi.new("uint8_t[]", size * group_count)
        get = raw_device_function(device, "vkGetRayTracingShaderGroupHandlesKHR")
        check(device.vk, get(device.handle, self.handle, 0, group_count, size * group_count, handles))
        raw = np.frombuffer(ffi.buffer(handles), dtype=np.uint8).reshape(group_count, size)
        stride = _align(size, props.handle_alignment)
        counts = (1, general - 1, group_count - general)
        starts, total = [], 0
        for count in counts:
            starts.append(total)
            total += _align(max(count, 1) * stride, props.base_alignment)
        usage = lib.VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR | lib.VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT
        self.table = self.owned.add(Buffer(device, total + props.base_alignment, usage, HOST))
        base = _align(self.table.address, props.base_alignment)
        skew = base - self.table.address
        out = self.table.bytes()
        group = 0
        for start, count in zip(starts, counts):
            for k in range(count):
                at = skew + start + k * stride
                out[at : at + size] = raw[group]
                group += 1
        self.regions = ffi.new("VkStridedDeviceAddressRegionKHR[4]")  # raygen, miss, hit, callable (empty)
        for i, (start, count) in enumerate(zip(starts, counts)):
            if count:
                self.regions[i].deviceAddress = base + start
                self.regions[i].stride = stride if i else _align(size, props.base_alignment)  # raygen: stride == size
                self.regions[i].size = stride * count if i else _align(size, props.base_alignment)

    def bind(self, cb: Any, sets: Sequence[Any], first: int = 0) -> None:
        lib, ffi = self.device.vk.lib, self.device.vk.ffi
        lib.vkCmdBindPipeline(cb, self.bind_point, self.handle)
        if sets:
            lib.vkCmdBindDescriptorSets(
                cb,
                self.bind_point,
                self.layout,
                first,
                len(sets),
                ffi.new("VkDescriptorSet[]", list(sets)),
                0,
                ffi.NULL,
            )

    def trace(self, cb: Any, width: int, height: int, depth: int = 1) -> None:
        r = self.regions
        self._trace(cb, r + 0, r + 1, r + 2, r + 3, width, height, depth)

    def destroy(self) -> None:
        self.owned.destroy()
        self.handle = None
