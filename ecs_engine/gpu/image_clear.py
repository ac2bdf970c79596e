"""An image cleared once, when it is made, and left in the layout its readers sample it in:
images whose contents a frame may read before anything wrote them (the shadow maps' layers no
view drew this frame, the ray-traced shadows' mask on a frame that traced nothing)."""

from __future__ import annotations

from typing import Any

from .image_barrier import image_barrier, record_image_barriers


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
    write = vk.VK_ACCESS_2_TRANSFER_WRITE_BIT
    top, transfer = vk.VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT

    def barrier(old: int, new: int, src: tuple[int, int], dst: tuple[int, int]) -> Any:
        # (`readers` and `read_access` may be synchronization-1 bits: those are the same values)
        stages = {"src_stage": src[0], "src_access": src[1], "dst_stage": dst[0], "dst_access": dst[1]}
        return image_barrier(vk, image, aspect=aspect, layers=layers, old=old, new=new, **stages)

    to_clear = barrier(vk.VK_IMAGE_LAYOUT_UNDEFINED, cleared_in, (top, 0), (transfer, write))
    to_read = barrier(cleared_in, layout, (transfer, write), (readers, read_access))

    def record(cb: Any) -> None:
        record_image_barriers(vk, cb, [to_clear])
        if depth:
            clear = vk.VkClearDepthStencilValue(depth=value, stencil=0)
            vk.vkCmdClearDepthStencilImage(cb, image, cleared_in, clear, 1, [whole])
        else:
            vk.vkCmdClearColorImage(cb, image, cleared_in, vk.VkClearColorValue(float32=[value] * 4), 1, [whole])
        record_image_barriers(vk, cb, [to_read])

    device.submit_once(record)
