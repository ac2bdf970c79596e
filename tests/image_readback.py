"""Tests' copies of an image to a host buffer and back, around the renderer's own barriers: each
image barrier through gpu/image_barrier.py (synchronization2), a target's colour read through
its own `record_copy` (gpu/offscreen.py). The barriers are coarse (every stage, every memory
access): a test's one-off copy, not a frame's.

    record_copy_out(vk, cb, image, buffer, extent, layout=READ_ONLY)   # an HDR colour, a depth
    pixels = target_corner(target, image, size, layout)                # a colour image, via a target
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ecs_engine.gpu.image_barrier import image_barrier, record_image_barriers


def transition(vk: Any, cb: Any, image: Any, old: int, new: int, aspect: int | None = None) -> None:
    """`image` (a VkImage handle) from layout `old` to `new`, everything before it done and
    visible to everything after (mip 0, layer 0; `aspect` colour unless given)."""
    every = vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT
    memory = vk.VK_ACCESS_2_MEMORY_READ_BIT | vk.VK_ACCESS_2_MEMORY_WRITE_BIT
    aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT if aspect is None else aspect
    barrier = image_barrier(
        vk,
        image,
        aspect=aspect,
        old=old,
        new=new,
        src_stage=every,
        src_access=memory,
        dst_stage=every,
        dst_access=memory,
    )
    record_image_barriers(vk, cb, [barrier])


def region(vk: Any, extent: tuple[int, int], aspect: int | None = None) -> Any:
    """The VkBufferImageCopy of the `extent` corner of mip 0, rows packed in the buffer."""
    aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT if aspect is None else aspect
    return vk.VkBufferImageCopy(
        bufferOffset=0,
        bufferRowLength=0,
        bufferImageHeight=0,
        imageSubresource=vk.VkImageSubresourceLayers(aspectMask=aspect, mipLevel=0, baseArrayLayer=0, layerCount=1),
        imageOffset=vk.VkOffset3D(0, 0, 0),
        imageExtent=vk.VkExtent3D(extent[0], extent[1], 1),
    )


def record_copy_out(
    vk: Any, cb: Any, image: Any, buffer: Any, extent: tuple[int, int], layout: int, aspect: int | None = None
) -> None:
    """Record the copy of `image`'s `extent` corner (a VkImage in `layout`, left so) into
    `buffer` (a gpu/memory.py Buffer with transfer-dst usage)."""
    src = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
    transition(vk, cb, image, layout, src, aspect)
    vk.vkCmdCopyImageToBuffer(cb, image, src, buffer.handle, 1, [region(vk, extent, aspect)])
    transition(vk, cb, image, src, layout, aspect)


def record_copy_in(vk: Any, cb: Any, buffer: Any, image: Any, extent: tuple[int, int]) -> None:
    """Record the copy of `buffer` into `image`'s `extent` corner (a colour VkImage that must be
    in TRANSFER_DST_OPTIMAL)."""
    dst = vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL
    vk.vkCmdCopyBufferToImage(cb, buffer.handle, image, dst, 1, [region(vk, extent)])


def target_corner(target: Any, image: Any, size: tuple[int, int], layout: int) -> np.ndarray:
    """The (height, width, 3) int64 `size` corner of a colour `image` (a gpu/memory.py Image of
    `target`'s format, left in `layout`), copied by the headless `target`'s own record_copy into
    its host buffer (which the next frame's readback overwrites)."""
    device = target.device
    vk = device.vk
    w, h = size
    src = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL

    def record(cb: Any) -> None:
        transition(vk, cb, image.handle, layout, src)
        target.record_copy(cb, image.handle, size)
        transition(vk, cb, image.handle, src, layout)

    device.submit_once(record)
    return target.readback.bytes()[: w * h * 4].reshape(h, w, 4)[..., :3].astype(np.int64)
