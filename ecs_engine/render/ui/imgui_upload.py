"""ImGui's textures (the font atlas, new glyphs, user images) copied to their Vulkan images: the
rectangles ImGui asks for, through a staging buffer, in one submission of their own (rare: not
per frame). Apart from imgui_pass.py for its size."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ...gpu.memory import HOST, Buffer

if TYPE_CHECKING:
    from ...gpu.device import Device


def upload_rects(device: Device, image: Any, tex: Any, rects: list[tuple[int, int, int, int]], fresh: bool) -> None:
    """Copy rectangles (x, y, w, h) of ImGui texture `tex`'s pixels to `image` (a VkImage in
    SHADER_READ_ONLY_OPTIMAL, or never written when `fresh`), left in SHADER_READ_ONLY_OPTIMAL."""
    vk = device.vk
    if tex.bytes_per_pixel != 4:
        raise ValueError(f"ImGui texture format {tex.format} is not RGBA32")
    pixels = np.asarray(tex.get_pixels_array(), dtype=np.uint8).reshape(tex.height, tex.width, 4)
    parts = [np.ascontiguousarray(pixels[y : y + h, x : x + w]) for x, y, w, h in rects]
    staging = Buffer(device, max(sum(p.nbytes for p in parts), 4), vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, HOST)
    regions = []
    offset = 0
    raw = staging.bytes()
    for (x, y, w, h), part in zip(rects, parts):
        raw[offset : offset + part.nbytes] = part.reshape(-1)
        regions.append(
            vk.VkBufferImageCopy(
                bufferOffset=offset,
                bufferRowLength=0,
                bufferImageHeight=0,
                imageSubresource=vk.VkImageSubresourceLayers(
                    aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0, baseArrayLayer=0, layerCount=1
                ),
                imageOffset=vk.VkOffset3D(x, y, 0),
                imageExtent=vk.VkExtent3D(w, h, 1),
            )
        )
        offset += part.nbytes
    old = vk.VK_IMAGE_LAYOUT_UNDEFINED if fresh else vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL

    def record(cb: Any) -> None:
        rng = vk.VkImageSubresourceRange(
            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=0, levelCount=1, baseArrayLayer=0, layerCount=1
        )
        to_copy = vk.VkImageMemoryBarrier(
            srcAccessMask=0 if fresh else vk.VK_ACCESS_SHADER_READ_BIT,
            dstAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT,
            oldLayout=old,
            newLayout=vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            image=image,
            subresourceRange=rng,
        )
        vk.vkCmdPipelineBarrier(
            cb,
            vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
            vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
            0,
            0,
            None,
            0,
            None,
            1,
            [to_copy],
        )
        vk.vkCmdCopyBufferToImage(
            cb, staging.handle, image, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, len(regions), regions
        )
        to_read = vk.VkImageMemoryBarrier(
            srcAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_SHADER_READ_BIT,
            oldLayout=vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
            newLayout=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            image=image,
            subresourceRange=rng,
        )
        vk.vkCmdPipelineBarrier(
            cb,
            vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
            vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
            0,
            0,
            None,
            0,
            None,
            1,
            [to_read],
        )

    try:
        device.submit_once(record)  # rare: the font atlas, new glyphs, user images
    finally:
        staging.destroy()
