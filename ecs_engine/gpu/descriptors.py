"""Descriptor set layouts, pools and buffer writes."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .device import Device
    from .memory import Buffer


class DescriptorSetLayout:
    """bindings: (binding, descriptor type, shader stage flags), one descriptor each, or
    (binding, type, stages, count) for an array of `count`."""

    def __init__(self, device: Device, bindings: Sequence[tuple[int, ...]]) -> None:
        vk = device.vk
        self.device = device
        self.bindings = [(*b, 1) if len(b) == 3 else tuple(b) for b in bindings]
        self.handle = vk.vkCreateDescriptorSetLayout(
            device.handle,
            vk.VkDescriptorSetLayoutCreateInfo(
                pBindings=[
                    vk.VkDescriptorSetLayoutBinding(binding=b, descriptorType=t, descriptorCount=n, stageFlags=s)
                    for b, t, s, n in self.bindings
                ]
            ),
            None,
        )

    def destroy(self) -> None:
        if self.handle is not None:
            self.device.vk.vkDestroyDescriptorSetLayout(self.device.handle, self.handle, None)
            self.handle = None


class DescriptorPool:
    def __init__(self, device: Device, max_sets: int, sizes: dict[int, int]) -> None:
        vk = device.vk
        self.device = device
        self.handle = vk.vkCreateDescriptorPool(
            device.handle,
            vk.VkDescriptorPoolCreateInfo(
                maxSets=max_sets,
                pPoolSizes=[vk.VkDescriptorPoolSize(type=t, descriptorCount=n) for t, n in sizes.items()],
            ),
            None,
        )

    def allocate(self, layout: DescriptorSetLayout) -> Any:
        vk = self.device.vk
        return vk.vkAllocateDescriptorSets(
            self.device.handle,
            vk.VkDescriptorSetAllocateInfo(
                descriptorPool=self.handle, descriptorSetCount=1, pSetLayouts=[layout.handle]
            ),
        )[0]

    def destroy(self) -> None:
        if self.handle is not None:
            self.device.objects_version += 1
            self.device.vk.vkDestroyDescriptorPool(self.device.handle, self.handle, None)
            self.handle = None


def write_buffers(device: Device, descriptor_set: Any, writes: Sequence[tuple[int, int, Buffer]]) -> None:
    """Point bindings of a set at whole buffers: (binding, descriptor type, buffer)."""
    vk = device.vk
    device.objects_version += 1
    vk.vkUpdateDescriptorSets(
        device.handle,
        len(writes),
        [
            vk.VkWriteDescriptorSet(
                dstSet=descriptor_set,
                dstBinding=binding,
                dstArrayElement=0,
                descriptorCount=1,
                descriptorType=kind,
                pBufferInfo=[buffer.descriptor()],
            )
            for binding, kind, buffer in writes
        ],
        0,
        None,
    )


def write_images(device: Device, descriptor_set: Any, binding: int, infos: Sequence[Any]) -> None:
    """Point a combined image sampler array binding at `infos` (VkDescriptorImageInfo), from element 0."""
    vk = device.vk
    device.objects_version += 1
    vk.vkUpdateDescriptorSets(
        device.handle,
        1,
        [
            vk.VkWriteDescriptorSet(
                dstSet=descriptor_set,
                dstBinding=binding,
                dstArrayElement=0,
                descriptorCount=len(infos),
                descriptorType=vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                pImageInfo=list(infos),
            )
        ],
        0,
        None,
    )


def write_acceleration_structure(device: Device, descriptor_set: Any, binding: int, handle: Any) -> None:
    """Point an acceleration-structure binding at a top level (raw call: the binding's
    constructor leaves descriptorCount at 0 for this type, whose data travels in pNext)."""
    vk, lib, ffi = device.vk, device.vk.lib, device.vk.ffi
    structures = ffi.new("VkAccelerationStructureKHR[1]", [handle])
    data = ffi.new(
        "VkWriteDescriptorSetAccelerationStructureKHR*",
        {
            "sType": lib.VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET_ACCELERATION_STRUCTURE_KHR,
            "accelerationStructureCount": 1,
            "pAccelerationStructures": structures,
        },
    )
    write = ffi.new(
        "VkWriteDescriptorSet*",
        {
            "sType": vk.VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
            "pNext": data,
            "dstSet": descriptor_set,
            "dstBinding": binding,
            "descriptorCount": 1,
            "descriptorType": lib.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR,
        },
    )
    device.objects_version += 1
    lib.vkUpdateDescriptorSets(device.handle, 1, write, 0, ffi.NULL)


def write_set(
    device: Device,
    descriptor_set: Any,
    *,
    storage_buffers: Sequence[tuple[int, Buffer]] = (),
    samplers: Sequence[tuple[int, Any, Any, int]] = (),
    storage_images: Sequence[tuple[int, Any]] = (),
) -> None:
    """Point bindings of a set, one descriptor each, in one update: storage buffers (binding,
    buffer), combined image samplers (binding, sampler, view, layout) and storage images in the
    GENERAL layout (binding, view)."""
    vk = device.vk
    writes = [
        vk.VkWriteDescriptorSet(
            dstSet=descriptor_set,
            dstBinding=binding,
            descriptorCount=1,
            descriptorType=vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
            pBufferInfo=[buffer.descriptor()],
        )
        for binding, buffer in storage_buffers
    ]
    writes += [
        vk.VkWriteDescriptorSet(
            dstSet=descriptor_set,
            dstBinding=binding,
            descriptorCount=1,
            descriptorType=vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
            pImageInfo=[vk.VkDescriptorImageInfo(sampler=sampler, imageView=view, imageLayout=layout)],
        )
        for binding, sampler, view, layout in samplers
    ]
    writes += [
        vk.VkWriteDescriptorSet(
            dstSet=descriptor_set,
            dstBinding=binding,
            descriptorCount=1,
            descriptorType=vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
            pImageInfo=[vk.VkDescriptorImageInfo(imageView=view, imageLayout=vk.VK_IMAGE_LAYOUT_GENERAL)],
        )
        for binding, view in storage_images
    ]
    device.objects_version += 1
    vk.vkUpdateDescriptorSets(device.handle, len(writes), writes, 0, None)
