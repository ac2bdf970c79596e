"""ImGui's textures (the font atlas, new glyphs, user images) copied to their Vulkan images: the
rectangles ImGui asks for, through a staging buffer, in one submission of their own (rare: not
per frame). Apart from imgui_pass.py for its size."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ...gpu.image_barrier import image_barrier, record_image_barriers
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
    read_only, dst = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL
    old = vk.VK_IMAGE_LAYOUT_UNDEFINED if fresh else read_only
    fragment, transfer = vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT
    read, write = vk.VK_ACCESS_2_SHADER_READ_BIT, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT
    color = vk.VK_IMAGE_ASPECT_COLOR_BIT
    to_copy = image_barrier(
        vk,
        image,
        aspect=color,
        old=old,
        new=dst,
        src_stage=fragment | vk.VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT,
        src_access=0 if fresh else read,
        dst_stage=transfer,
        dst_access=write,
    )
    to_read = image_barrier(
        vk,
        image,
        aspect=color,
        old=dst,
        new=read_only,
        src_stage=transfer,
        src_access=write,
        dst_stage=fragment,
        dst_access=read,
    )

    def record(cb: Any) -> None:
        record_image_barriers(vk, cb, [to_copy])
        vk.vkCmdCopyBufferToImage(cb, staging.handle, image, dst, len(regions), regions)
        record_image_barriers(vk, cb, [to_read])

    try:
        device.submit_once(record)  # rare: the font atlas, new glyphs, user images
    finally:
        staging.destroy()
