"""Window target: surface format and present mode choice, the swapchain with its images' views
and the scene's attachments, recreated on resize; acquire and present."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import UsageError
from .functions import device_function, instance_function, raw_device_function
from .memory import HOST, Buffer
from .scene_attachments import Form, SceneAttachments, TargetForm

if TYPE_CHECKING:
    from .device import Device

PRESENT_MODES = {
    "fifo": "VK_PRESENT_MODE_FIFO_KHR",
    "mailbox": "VK_PRESENT_MODE_MAILBOX_KHR",
    "immediate": "VK_PRESENT_MODE_IMMEDIATE_KHR",
}


class OutOfDate(Exception):
    """The swapchain no longer matches the window: recreate it and skip this frame."""


class Swapchain(TargetForm):
    def __init__(
        self,
        device: Device,
        surface: Any,
        framebuffer_size: Callable[[], tuple[int, int]],
        present: str = "fifo",
        samples: int = 1,
        hdr: bool = False,
    ) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.samples = samples  # MSAA of the scene's attachments
        self.form = Form.HDR if hdr or samples > 1 else Form.DIRECT
        self.surface = surface
        self.framebuffer_size = framebuffer_size
        inst = device.instance
        self._caps = instance_function(inst, "vkGetPhysicalDeviceSurfaceCapabilitiesKHR")
        formats = instance_function(inst, "vkGetPhysicalDeviceSurfaceFormatsKHR")(device.physical, surface)
        modes = instance_function(inst, "vkGetPhysicalDeviceSurfacePresentModesKHR")(device.physical, surface)
        self._modes = list(modes)
        self.present_name = present  # fifo, mailbox or immediate
        self.present_mode = self.present_mode_for(present)
        srgb = [
            f
            for f in formats
            if f.format in (vk.VK_FORMAT_B8G8R8A8_SRGB, vk.VK_FORMAT_R8G8B8A8_SRGB)
            and f.colorSpace == vk.VK_COLOR_SPACE_SRGB_NONLINEAR_KHR
        ]
        chosen = srgb[0] if srgb else formats[0]
        self.color_format, self.color_space = chosen.format, chosen.colorSpace
        self.final_layout = vk.VK_IMAGE_LAYOUT_PRESENT_SRC_KHR
        self._create_fn = device_function(device, "vkCreateSwapchainKHR")
        self._destroy_fn = device_function(device, "vkDestroySwapchainKHR")
        self._images_fn = device_function(device, "vkGetSwapchainImagesKHR")
        # raw entry points: the binding's wrappers raise on VK_SUBOPTIMAL_KHR, a success code
        # that still acquires an image and signals the semaphore
        self._acquire_raw = raw_device_function(device, "vkAcquireNextImageKHR")
        self._present_raw = raw_device_function(device, "vkQueuePresentKHR")
        self._index = vk.ffi.new("uint32_t*")
        self.handle = None
        self.views: list[Any] = []
        # per image, what the renderer's `render` takes to draw into it (output_image): its index
        self.framebuffers: list[int] = []
        self.render_finished: list[Any] = []
        self._forms: dict[Form, SceneAttachments] = {}  # the scene's attachments of each form used
        self.width = self.height = 0
        self.recreations = 0
        # screenshots: an image can be copied out when the surface allows TRANSFER_SRC
        supported = self._caps(device.physical, surface).supportedUsageFlags
        self.copy_usage = supported & vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        self.readback_image: int | None = None  # the image index the next frame reads back (take_readback)
        self._readback: Buffer | None = None
        self._readback_size: tuple[int, int] = (0, 0)
        self._build()

    def _build(self) -> None:
        vk = self.vk
        caps = self._caps(self.device.physical, self.surface)
        if caps.currentExtent.width != 0xFFFFFFFF:
            width, height = caps.currentExtent.width, caps.currentExtent.height
        else:
            w, h = self.framebuffer_size()
            width = min(max(w, caps.minImageExtent.width), caps.maxImageExtent.width)
            height = min(max(h, caps.minImageExtent.height), caps.maxImageExtent.height)
        count = caps.minImageCount + 1
        if caps.maxImageCount:
            count = min(count, caps.maxImageCount)
        old = self.handle
        self.handle = self._create_fn(
            self.device.handle,
            vk.VkSwapchainCreateInfoKHR(
                surface=self.surface,
                minImageCount=count,
                imageFormat=self.color_format,
                imageColorSpace=self.color_space,
                imageExtent=vk.VkExtent2D(width, height),
                imageArrayLayers=1,
                imageUsage=vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | self.copy_usage,
                imageSharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
                preTransform=caps.currentTransform,
                compositeAlpha=vk.VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR,
                presentMode=self.present_mode,
                clipped=vk.VK_TRUE,
                oldSwapchain=old,
            ),
            None,
        )
        if old is not None:
            self._destroy_fn(self.device.handle, old, None)
        self.width, self.height = width, height
        self.images = self._images_fn(self.device.handle, self.handle)
        self._forms = {self.form: self._attachments_for(self.form)}
        for image in self.images:
            view = vk.vkCreateImageView(
                self.device.handle,
                vk.VkImageViewCreateInfo(
                    image=image,
                    viewType=vk.VK_IMAGE_VIEW_TYPE_2D,
                    format=self.color_format,
                    subresourceRange=vk.VkImageSubresourceRange(
                        aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT,
                        baseMipLevel=0,
                        levelCount=1,
                        baseArrayLayer=0,
                        layerCount=1,
                    ),
                ),
                None,
            )
            self.framebuffers.append(len(self.views))
            self.views.append(view)
            # one per image: a semaphore waited on by present is free again only once that image
            # is acquired again
            self.render_finished.append(vk.vkCreateSemaphore(self.device.handle, vk.VkSemaphoreCreateInfo(), None))

    def _release(self) -> None:
        vk = self.vk
        for view in self.views:
            vk.vkDestroyImageView(self.device.handle, view, None)
        for sem in self.render_finished:
            vk.vkDestroySemaphore(self.device.handle, sem, None)
        self.framebuffers, self.views, self.render_finished = [], [], []
        self._release_forms()

    def _attachments_for(self, form: Form) -> SceneAttachments:
        return SceneAttachments(self.device, self.width, self.height, self.samples, form)

    def output_image(self, output: Any) -> tuple[Any, Any]:
        """The swapchain image `output` (an entry of `framebuffers`: its index) and its view."""
        return self.images[output], self.views[output]

    def present_mode_for(self, present: str) -> int:
        """The VkPresentModeKHR of a name; UsageError when the surface does not offer it."""
        wanted = getattr(self.vk, PRESENT_MODES[present])
        if wanted not in self._modes:
            raise UsageError(f"present mode {present!r} is not supported here; try --present fifo")
        return wanted

    def set_present(self, present: str) -> None:
        """Switch present mode (fifo, mailbox, immediate): the swapchain is rebuilt."""
        self.present_mode = self.present_mode_for(present)
        self.present_name = present
        self.recreate()

    def recreate(self) -> None:
        self.device.wait_idle()
        self._release()
        self._build()
        self.recreations += 1

    def acquire(self, semaphore: Any) -> tuple[int, bool]:
        """(image index, suboptimal). Raises OutOfDate when no image could be acquired."""
        vk = self.vk
        result = self._acquire_raw(self.device.handle, self.handle, 2**64 - 1, semaphore, vk.ffi.NULL, self._index)
        if result == vk.VK_ERROR_OUT_OF_DATE_KHR:
            raise OutOfDate
        if result not in (vk.VK_SUCCESS, vk.VK_SUBOPTIMAL_KHR):
            raise RuntimeError(f"vkAcquireNextImageKHR failed with VkResult {result}")
        return int(self._index[0]), result == vk.VK_SUBOPTIMAL_KHR

    def present(self, index: int) -> bool:
        """Queue the image; False when the swapchain should be recreated."""
        vk = self.vk
        info = vk.VkPresentInfoKHR(
            pWaitSemaphores=[self.render_finished[index]], pSwapchains=[self.handle], pImageIndices=[index]
        )
        result = self._present_raw(self.device.queue, vk.ffi.addressof(info))
        if result in (vk.VK_ERROR_OUT_OF_DATE_KHR, vk.VK_SUBOPTIMAL_KHR):
            return False
        if result != vk.VK_SUCCESS:
            raise RuntimeError(f"vkQueuePresentKHR failed with VkResult {result}")
        return True

    def take_readback(self) -> bool:
        """Whether this frame's image is read back (`readback_image` was set to it; cleared
        here): the output graph then ends with its readback pass (render/passes/readback.py),
        which calls record_copy. UsageError when the surface's images cannot be copied."""
        if self.readback_image is None:
            return False
        if not self.copy_usage:
            self.readback_image = None
            raise UsageError(
                "this window's swapchain images cannot be copied (no TRANSFER_SRC usage): "
                "no screenshot; run with --headless for one"
            )
        self.readback_image = None
        return True

    def record_copy(self, cb: Any, image: Any, extent: tuple[int, int]) -> None:
        """Copy `image` (this frame's, in TRANSFER_SRC layout: the graph's barrier, which takes
        it to PRESENT_SRC after) to a host buffer; `pixels()` reads it once the frame is done."""
        vk = self.vk
        size = (int(extent[0]), int(extent[1]))
        if self._readback is None:
            self._readback = Buffer(self.device, 4 * size[0] * size[1], vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
        self._readback = self._readback.grown(4 * size[0] * size[1])
        self._readback_size = size
        region = vk.VkBufferImageCopy(
            bufferOffset=0,
            bufferRowLength=0,
            bufferImageHeight=0,
            imageSubresource=vk.VkImageSubresourceLayers(
                aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0, baseArrayLayer=0, layerCount=1
            ),
            imageOffset=vk.VkOffset3D(0, 0, 0),
            imageExtent=vk.VkExtent3D(size[0], size[1], 1),
        )
        transfer = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
        vk.vkCmdCopyImageToBuffer(cb, image, transfer, self._readback.handle, 1, [region])
        to_host = vk.VkBufferMemoryBarrier(
            srcAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_HOST_READ_BIT,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            buffer=self._readback.handle,
            offset=0,
            size=self._readback.size,
        )
        vk.vkCmdPipelineBarrier(
            cb, vk.VK_PIPELINE_STAGE_TRANSFER_BIT, vk.VK_PIPELINE_STAGE_HOST_BIT, 0, 0, None, 1, [to_host], 0, None
        )

    def pixels(self) -> np.ndarray | None:
        """(height, width, 4) uint8 RGBA of the last image read back (after its frame's fence),
        or None when none was."""
        if self._readback is None:
            return None
        width, height = self._readback_size
        raw = self._readback.bytes()[: 4 * width * height].reshape(height, width, 4)
        if self.color_format in (self.vk.VK_FORMAT_B8G8R8A8_SRGB, self.vk.VK_FORMAT_B8G8R8A8_UNORM):
            return raw[..., [2, 1, 0, 3]].copy()
        return raw.copy()

    def destroy(self) -> None:
        self.device.wait_idle()
        if self._readback is not None:
            self._readback.destroy()
            self._readback = None
        self._release()
        if self.handle is not None:
            self._destroy_fn(self.device.handle, self.handle, None)
            self.handle = None
