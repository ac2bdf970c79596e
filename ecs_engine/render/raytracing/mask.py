"""The ray-traced shadows' mask (render/raytracing/shadows.py): per pixel and shadow-casting light, the
fraction of its rays that reached the light, four lights a layer (RGBA8, one per channel). The
deferred lighting reads it (a storage image, so both stay in the GENERAL layout); made with the
target's attachments, cleared to 1 (lit) so a frame that traces nothing reads no shadow."""

from __future__ import annotations

from typing import Any

from ...gpu.memory import Image
from ..layouts import MAX_RAY_LIGHTS

LAYERS = MAX_RAY_LIGHTS // 4


class ShadowMask:
    def __init__(self, device: Any, width: int, height: int) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height = width, height
        usage = vk.VK_IMAGE_USAGE_STORAGE_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
        self.image = Image(
            device, width, height, vk.VK_FORMAT_R8G8B8A8_UNORM, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT, layers=LAYERS
        )
        try:
            self._clear()
        except BaseException:
            self.image.destroy()
            raise

    @property
    def view(self) -> Any:
        return self.image.view

    def _clear(self) -> None:
        vk = self.device.vk
        general = vk.VK_IMAGE_LAYOUT_GENERAL
        whole = vk.VkImageSubresourceRange(
            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=0, levelCount=1, baseArrayLayer=0, layerCount=LAYERS
        )

        def barrier(old: int, src: int, dst: int) -> Any:
            return vk.VkImageMemoryBarrier(
                srcAccessMask=src,
                dstAccessMask=dst,
                oldLayout=old,
                newLayout=general,
                srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                image=self.image.handle,
                subresourceRange=whole,
            )

        to_clear = barrier(vk.VK_IMAGE_LAYOUT_UNDEFINED, 0, vk.VK_ACCESS_TRANSFER_WRITE_BIT)
        cleared = barrier(general, vk.VK_ACCESS_TRANSFER_WRITE_BIT, vk.VK_ACCESS_SHADER_READ_BIT)
        one = vk.VkClearColorValue(float32=[1.0, 1.0, 1.0, 1.0])
        top, transfer = vk.VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, vk.VK_PIPELINE_STAGE_TRANSFER_BIT
        shaders = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT

        def record(cb: Any) -> None:
            vk.vkCmdPipelineBarrier(cb, top, transfer, 0, 0, None, 0, None, 1, [to_clear])
            vk.vkCmdClearColorImage(cb, self.image.handle, general, one, 1, [whole])
            vk.vkCmdPipelineBarrier(cb, transfer, shaders, 0, 0, None, 0, None, 1, [cleared])

        self.device.submit_once(record)

    def destroy(self) -> None:
        self.image.destroy()
