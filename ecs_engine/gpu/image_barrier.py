"""The one constructor of image memory barriers (synchronization2): a layout transition and
memory dependency over a range of an image's mips and layers, and a batch of them recorded with
vkCmdPipelineBarrier2. The frame graph (render/graph/barriers.py), the shadow maps' and the
render textures' barriers and the one-off uploads and clears all make theirs here, so that each
field is named in one place (the queue families ignored: no ownership transfers)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


def image_barrier(
    vk: Any,
    image: Any,
    *,
    aspect: int,
    old: int,
    new: int,
    src_stage: int,
    src_access: int,
    dst_stage: int,
    dst_access: int,
    base_mip: int = 0,
    mips: int = 1,
    base_layer: int = 0,
    layers: int = 1,
) -> Any:
    """A VkImageMemoryBarrier2 of `image`'s `aspect` over mips base_mip.. and layers
    base_layer.. (`mips` and `layers` of each), from layout `old` to `new`, after the
    (src_stage, src_access) work and before the (dst_stage, dst_access) work."""
    return vk.VkImageMemoryBarrier2(
        srcStageMask=src_stage,
        srcAccessMask=src_access,
        dstStageMask=dst_stage,
        dstAccessMask=dst_access,
        oldLayout=old,
        newLayout=new,
        srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
        dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
        image=image,
        subresourceRange=vk.VkImageSubresourceRange(
            aspectMask=aspect, baseMipLevel=base_mip, levelCount=mips, baseArrayLayer=base_layer, layerCount=layers
        ),
    )


def dependency(vk: Any, images: Sequence[Any], buffers: Sequence[Any] = (), memory: Sequence[Any] = ()) -> Any:
    """The VkDependencyInfo of these barriers (image, buffer and global ones) for one
    vkCmdPipelineBarrier2; it holds copies of them, so it can be kept and recorded again
    (vk.ffi.addressof(info) for the raw call)."""
    return vk.VkDependencyInfo(
        pMemoryBarriers=list(memory) or None,
        pBufferMemoryBarriers=list(buffers) or None,
        pImageMemoryBarriers=list(images) or None,
    )


def record_image_barriers(vk: Any, cb: Any, barriers: Sequence[Any]) -> None:
    """Record `barriers` (image_barrier's) as one vkCmdPipelineBarrier2 into `cb`."""
    vk.vkCmdPipelineBarrier2(cb, dependency(vk, barriers))
