"""The target image's transition to its final layout after the output (render/frame/output_passes.py;
render/passes/output_graph.py's graph places every barrier before it), as an explicit
vkCmdPipelineBarrier2 call: COLOR_ATTACHMENT_OPTIMAL -> the target's final layout, the colour
writes made visible to the readback copy (TRANSFER_SRC) or, for present, ordered before the
colour-output stage the swapchain's readback barrier starts from (the submission's signal covers
presentation). The graph's own transition to PRESENT_SRC ends in no stage, which that readback
barrier could not follow; it goes when readback is a pass of the renderer's graph.
"""

from __future__ import annotations

from typing import Any


def _final_scope(vk: Any, final_layout: int) -> tuple[int, int]:
    """(stage, access) that read the target after the output, by its final layout."""
    if final_layout == vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL:
        return vk.VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT
    return vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0


class OutputBarriers:
    """The final transition of one target image, made once and recorded with a raw call."""

    def __init__(self, vk: Any, image: Any, final_layout: int) -> None:
        color_stage = vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT
        color_write = vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT
        attachment = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
        whole = vk.VkImageSubresourceRange(
            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=0, levelCount=1, baseArrayLayer=0, layerCount=1
        )

        def dependency(src: tuple[int, int], dst: tuple[int, int], old: int, new: int) -> Any:
            barrier = vk.VkImageMemoryBarrier2(
                srcStageMask=src[0],
                srcAccessMask=src[1],
                dstStageMask=dst[0],
                dstAccessMask=dst[1],
                oldLayout=old,
                newLayout=new,
                srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                image=image,
                subresourceRange=whole,
            )
            info = vk.VkDependencyInfo(pImageMemoryBarriers=[barrier])
            self._keep.append((barrier, info))
            return vk.ffi.addressof(info)

        self._keep: list[Any] = []
        final = _final_scope(vk, final_layout)
        self.after_ptr = dependency((color_stage, color_write), final, attachment, final_layout)

    def after(self, lib: Any, cb: Any) -> None:
        lib.vkCmdPipelineBarrier2(cb, self.after_ptr)
