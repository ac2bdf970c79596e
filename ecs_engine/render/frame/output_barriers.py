"""The target image's layout transitions around the output rendering (render/frame/output_passes.py:
the tone map and the overlay drawn with vkCmdBeginRendering into the swapchain or offscreen
image), as explicit vkCmdPipelineBarrier2 calls. The scene's rendering does not touch the
target in the hdr and deferred forms, so nothing else moves the image between "whatever the last
frame or the presentation engine left" and the layout its reader wants (readback: TRANSFER_SRC;
present: PRESENT_SRC). The renderer's frame graph is to take these over: they are kept here, in
one place, so that it replaces one class.

- `before`: UNDEFINED -> COLOR_ATTACHMENT_OPTIMAL (the tone map writes every pixel, so the old
  contents go), after the acquire semaphore's wait (colour output stage) and the last frame's
  readback copy of the same image (transfer stage);
- `after`: COLOR_ATTACHMENT_OPTIMAL -> the target's final layout, the colour writes made visible
  to the readback copy (TRANSFER_SRC) or, for present, ordered before the colour-output stage
  the swapchain's readback barrier starts from (the submission's signal covers presentation).
"""

from __future__ import annotations

from typing import Any


def _final_scope(vk: Any, final_layout: int) -> tuple[int, int]:
    """(stage, access) that read the target after the output, by its final layout."""
    if final_layout == vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL:
        return vk.VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT
    return vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0


class OutputBarriers:
    """The two transitions of one target image, made once and recorded with raw calls."""

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
        self.before_ptr = dependency(
            (color_stage | vk.VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0),
            (color_stage, color_write | vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT),
            vk.VK_IMAGE_LAYOUT_UNDEFINED,
            attachment,
        )
        final = _final_scope(vk, final_layout)
        self.after_ptr = dependency((color_stage, color_write), final, attachment, final_layout)

    def before(self, lib: Any, cb: Any) -> None:
        lib.vkCmdPipelineBarrier2(cb, self.before_ptr)

    def after(self, lib: Any, cb: Any) -> None:
        lib.vkCmdPipelineBarrier2(cb, self.after_ptr)
