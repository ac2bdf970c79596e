"""Headless render target: a colour image the frame's output is drawn into, the scene's
attachments of its forms, and readback to NumPy."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .memory import HOST, Buffer, Image
from .scene_attachments import Form, SceneAttachments, TargetForm

if TYPE_CHECKING:
    from .device import Device


class OffscreenTarget(TargetForm):
    """Renders into an sRGB RGBA8 image that can be copied to a host buffer each frame.

    One colour image is shared by the frames in flight: the renderer waits for a frame's fence
    before reading its pixels, and frames in flight are ordered on the single queue. `framebuffer`
    names that image as the renderer's `render` takes it (a swapchain has one per image)."""

    def __init__(self, device: Device, width: int, height: int, samples: int = 1, hdr: bool = False) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height = width, height
        self.samples = samples  # MSAA of the scene's attachments (the target itself has one sample)
        self.form = Form.HDR if hdr or samples > 1 else Form.DIRECT
        self.color_format = vk.VK_FORMAT_R8G8B8A8_SRGB
        self.final_layout = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL  # the output graph's readback pass leaves it so
        self.color = Image(
            device,
            width,
            height,
            self.color_format,
            vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
            vk.VK_IMAGE_ASPECT_COLOR_BIT,
        )
        self.framebuffer = self.color  # what the renderer draws the output into (output_image)
        self._forms: dict[Form, SceneAttachments] = {}
        try:
            self._forms[self.form] = self._attachments_for(self.form)
        except BaseException:
            self.color.destroy()
            raise
        self.readback = Buffer(device, width * height * 4, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)

    def _attachments_for(self, form: Form) -> SceneAttachments:
        return SceneAttachments(self.device, self.width, self.height, self.samples, form)

    def take_readback(self) -> bool:
        """Whether this frame's output is read back when the renderer is asked to: always (the
        output graph's readback pass, render/passes/readback.py, then calls record_copy)."""
        return True

    def record_copy(self, cb: Any, image: Any, extent: tuple[int, int]) -> None:
        """Copy `image` (the frame's output, in TRANSFER_SRC layout: the graph's barrier) to the
        host buffer, visible to the host once the frame's fence is signalled."""
        vk = self.device.vk
        region = vk.VkBufferImageCopy(
            bufferOffset=0,
            bufferRowLength=0,
            bufferImageHeight=0,
            imageSubresource=vk.VkImageSubresourceLayers(
                aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0, baseArrayLayer=0, layerCount=1
            ),
            imageOffset=vk.VkOffset3D(0, 0, 0),
            imageExtent=vk.VkExtent3D(min(extent[0], self.width), min(extent[1], self.height), 1),
        )
        vk.vkCmdCopyImageToBuffer(cb, image, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, self.readback.handle, 1, [region])
        barrier = vk.VkBufferMemoryBarrier(
            srcAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_HOST_READ_BIT,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            buffer=self.readback.handle,
            offset=0,
            size=self.readback.size,
        )
        vk.vkCmdPipelineBarrier(
            cb, vk.VK_PIPELINE_STAGE_TRANSFER_BIT, vk.VK_PIPELINE_STAGE_HOST_BIT, 0, 0, None, 1, [barrier], 0, None
        )

    def output_image(self, output: Any) -> tuple[Any, Any]:
        """(VkImage, view) of `output`: `framebuffer` (the colour image, which frames in flight
        share), or another gpu/memory.py Image of the colour format and size to draw into."""
        return output.handle, output.view

    def pixels(self) -> np.ndarray:
        """(height, width, 4) uint8 RGBA (sRGB-encoded), a copy of the last readback."""
        return self.readback.bytes().reshape(self.height, self.width, 4).copy()

    def destroy(self) -> None:
        self.readback.destroy()
        self._release_forms()
        self.color.destroy()
