"""Shadow maps: one 32-bit depth image with a layer per shadow view (a cascade, a spot light's
map; render/shadow_views.py), square, the depth-only render pass that draws a layer, a
framebuffer per layer, and the view and samplers the lighting reads them through.

Depth is reverse-Z, cleared to 0 (far); the comparison samplers compare with GREATER_OR_EQUAL,
so a receiver whose depth is at least the nearest caster's is lit. The filtering one is linear
(each tap a bilinear 2 x 2 comparison: percentage-closer filtering in hardware), the hard one
nearest; a third reads the depths themselves (PCSS looks for its blockers with it).
Frames in flight share the image: the render pass's dependencies order this frame's writes
after the previous frame's reads and before this frame's lighting.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .attachment import attachment
from .memory import DEVICE

if TYPE_CHECKING:
    from .device import Device

SHADOW_FORMAT_NAME = "VK_FORMAT_D32_SFLOAT"


def create_shadow_pass(device: Device) -> Any:
    vk = device.vk
    depth = attachment(
        vk,
        getattr(vk, SHADOW_FORMAT_NAME),
        1,
        vk.VK_ATTACHMENT_LOAD_OP_CLEAR,
        vk.VK_ATTACHMENT_STORE_OP_STORE,
        vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL,
    )
    subpass = vk.VkSubpassDescription(
        pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS,
        pDepthStencilAttachment=vk.VkAttachmentReference(
            attachment=0, layout=vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL
        ),
    )
    depth_stages = vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
    readers = vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
    depth_rw = vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
    dependencies = [
        # the previous frame's lighting read the layer (and its pass wrote it) before this clear
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=0,
            srcStageMask=readers | depth_stages,
            dstStageMask=depth_stages,
            srcAccessMask=vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
            dstAccessMask=depth_rw,
        ),
        # the depth written -> the lighting's reads (forward fragments, the deferred compute pass)
        vk.VkSubpassDependency(
            srcSubpass=0,
            dstSubpass=vk.VK_SUBPASS_EXTERNAL,
            srcStageMask=depth_stages,
            dstStageMask=readers,
            srcAccessMask=vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_SHADER_READ_BIT,
        ),
    ]
    return vk.vkCreateRenderPass(
        device.handle,
        vk.VkRenderPassCreateInfo(pAttachments=[depth], pSubpasses=[subpass], pDependencies=dependencies),
        None,
    )


class ShadowMaps:
    """`layers` square depth maps of `resolution` texels, drawn with `render_pass` (a
    create_shadow_pass; compatible ones may share pipelines)."""

    def __init__(self, device: Device, render_pass: Any, resolution: int, layers: int) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.resolution, self.layers = int(resolution), int(layers)
        self.image: Any = None
        self.allocation: Any = None
        self.array_view: Any = None
        self.layer_views: list[Any] = []
        self.framebuffers: list[Any] = []
        self.samplers: list[Any] = []
        fmt = getattr(vk, SHADOW_FORMAT_NAME)
        aspect = vk.VK_IMAGE_ASPECT_DEPTH_BIT
        try:
            self.image = vk.vkCreateImage(
                device.handle,
                vk.VkImageCreateInfo(
                    imageType=vk.VK_IMAGE_TYPE_2D,
                    format=fmt,
                    extent=vk.VkExtent3D(self.resolution, self.resolution, 1),
                    mipLevels=1,
                    arrayLayers=self.layers,
                    samples=1,
                    tiling=vk.VK_IMAGE_TILING_OPTIMAL,
                    usage=vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT,
                    sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
                    initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
                ),
                None,
            )
            req = vk.vkGetImageMemoryRequirements(device.handle, self.image)
            self.allocation = device.allocator.allocate(req, DEVICE, "image")
            vk.vkBindImageMemory(device.handle, self.image, self.allocation.memory, self.allocation.offset)

            def view(kind: int, first: int, count: int) -> Any:
                return vk.vkCreateImageView(
                    device.handle,
                    vk.VkImageViewCreateInfo(
                        image=self.image,
                        viewType=kind,
                        format=fmt,
                        subresourceRange=vk.VkImageSubresourceRange(
                            aspectMask=aspect, baseMipLevel=0, levelCount=1, baseArrayLayer=first, layerCount=count
                        ),
                    ),
                    None,
                )

            self.array_view = view(vk.VK_IMAGE_VIEW_TYPE_2D_ARRAY, 0, self.layers)
            for layer in range(self.layers):
                self.layer_views.append(view(vk.VK_IMAGE_VIEW_TYPE_2D, layer, 1))
                self.framebuffers.append(
                    vk.vkCreateFramebuffer(
                        device.handle,
                        vk.VkFramebufferCreateInfo(
                            renderPass=render_pass,
                            pAttachments=[self.layer_views[-1]],
                            width=self.resolution,
                            height=self.resolution,
                            layers=1,
                        ),
                        None,
                    )
                )
            kinds = ((vk.VK_FILTER_LINEAR, True), (vk.VK_FILTER_NEAREST, True), (vk.VK_FILTER_NEAREST, False))
            for filtering, compare in kinds:
                self.samplers.append(
                    vk.vkCreateSampler(
                        device.handle,
                        vk.VkSamplerCreateInfo(
                            magFilter=filtering,
                            minFilter=filtering,
                            addressModeU=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                            addressModeV=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                            addressModeW=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                            compareEnable=vk.VK_TRUE if compare else vk.VK_FALSE,
                            compareOp=vk.VK_COMPARE_OP_GREATER_OR_EQUAL,
                        ),
                        None,
                    )
                )
        except BaseException:
            self.destroy()
            raise

    def image_infos(self) -> list[Any]:
        """VkDescriptorImageInfo of the array with the filtering comparison sampler, the hard
        (nearest) one, and the plain nearest one that reads depths."""
        vk = self.vk
        layout = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL
        return [
            vk.VkDescriptorImageInfo(sampler=s, imageView=self.array_view, imageLayout=layout) for s in self.samplers
        ]

    def destroy(self) -> None:
        vk, handle = self.vk, self.device.handle
        for sampler in self.samplers:
            vk.vkDestroySampler(handle, sampler, None)
        for fb in self.framebuffers:
            vk.vkDestroyFramebuffer(handle, fb, None)
        for v in self.layer_views:
            vk.vkDestroyImageView(handle, v, None)
        if self.array_view is not None:
            vk.vkDestroyImageView(handle, self.array_view, None)
        if self.image is not None:
            vk.vkDestroyImage(handle, self.image, None)
        if self.allocation is not None:
            self.device.allocator.free(self.allocation)
        self.samplers, self.framebuffers, self.layer_views = [], [], []
        self.array_view = self.image = self.allocation = None
