"""An image cleared once, when it is made, and left in the layout its readers sample it in:
images whose contents a frame may read before anything wrote them (the shadow maps' layers no
view drew this frame, the ray-traced shadows' mask on a frame that traced nothing)."""

from __future__ import annotations

from typing import Any


def clear_once(
    device: Any, image: Any, *, depth: bool, layers: int, value: float, layout: int, readers: int, read_access: int
) -> None:
    """Clear every layer of `image` (mip 0; a depth image's depth, or a colour image's RGBA) to
    `value`, then move it to `layout` for `readers` (pipeline stages) reading with `read_access`;
    recorded, submitted and waited for (Device.submit_once)."""
    vk = device.vk
    aspect = vk.VK_IMAGE_ASPECT_DEPTH_BIT if depth else vk.VK_IMAGE_ASPECT_COLOR_BIT
    whole = vk.VkImageSubresourceRange(
        aspectMask=aspect, baseMipLevel=0, levelCount=1, baseArrayLayer=0, layerCount=layers
    )
    # a GENERAL image (a storage image) is cleared in place; others in TRANSFER_DST
    cleared_in = layout if layout == vk.VK_IMAGE_LAYOUT_GENERAL else vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL

    def barrier(old: int, new: int, src: int, dst: int) -> Any:
        return vk.VkImageMemoryBarrier(
            srcAccessMask=src,
            dstAccessMask=dst,
            oldLayout=old,
            newLayout=new,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            image=image,
            subresourceRange=whole,
        )

    write = vk.VK_ACCESS_TRANSFER_WRITE_BIT
    to_clear = barrier(vk.VK_IMAGE_LAYOUT_UNDEFINED, cleared_in, 0, write)
    to_read = barrier(cleared_in, layout, write, read_access)
    top, transfer = vk.VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, vk.VK_PIPELINE_STAGE_TRANSFER_BIT

    def record(cb: Any) -> None:
        vk.vkCmdPipelineBarrier(cb, top, transfer, 0, 0, None, 0, None, 1, [to_clear])
        if depth:
            clear = vk.VkClearDepthStencilValue(depth=value, stencil=0)
            vk.vkCmdClearDepthStencilImage(cb, image, cleared_in, clear, 1, [whole])
        else:
            vk.vkCmdClearColorImage(cb, image, cleared_in, vk.VkClearColorValue(float32=[value] * 4), 1, [whole])
        vk.vkCmdPipelineBarrier(cb, transfer, readers, 0, 0, None, 0, None, 1, [to_read])

    device.submit_once(record)
