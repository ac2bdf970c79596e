"""Shadow maps: one 32-bit depth image with a layer per shadow view (a cascade, a spot light's
map; render/shadow_views.py), square, the depth-only render pass that draws a layer, a
framebuffer per layer, and the view and samplers the lighting reads them through.

Depth is reverse-Z, cleared to 0 (far); the comparison samplers compare with GREATER_OR_EQUAL,
so a receiver whose depth is at least the nearest caster's is lit. The filtering one is linear
(each tap a bilinear 2 x 2 comparison: percentage-closer filtering in hardware), the hard one
nearest; a third reads the depths themselves (PCSS looks for its blockers with it).
Frames in flight share the image: the render pass's dependencies order this frame's writes
after the previous frame's reads and before this frame's lighting.

The editor shows each layer (preview_view: the depth in R, G and B, read through the plain
sampler) in the overlay, drawn after the lighting, where every layer is in READ_LAYOUT.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .attachment import attachment, create_framebuffer, make_render_pass
from .memory import Image

if TYPE_CHECKING:
    from .device import Device

SHADOW_FORMAT_NAME = "VK_FORMAT_D32_SFLOAT"
READ_LAYOUT_NAME = "VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL"  # after the shadow pass: sampled


def create_shadow_pass(device: Device, samples: int = 1) -> Any:
    """A depth-only pass: cleared, stored, then sampled (READ_LAYOUT); `samples` per pixel (the
    occlusion culling's early depth matches the target's MSAA, render/occlusion.py)."""
    vk = device.vk
    depth = attachment(
        vk,
        getattr(vk, SHADOW_FORMAT_NAME),
        samples,
        vk.VK_ATTACHMENT_LOAD_OP_CLEAR,
        vk.VK_ATTACHMENT_STORE_OP_STORE,
        getattr(vk, READ_LAYOUT_NAME),
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
    return make_render_pass(device, [depth], [subpass], dependencies)


class ShadowMaps:
    """`layers` square depth maps of `resolution` texels, drawn with `render_pass` (a
    create_shadow_pass; compatible ones may share pipelines)."""

    def __init__(self, device: Device, render_pass: Any, resolution: int, layers: int) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.resolution, self.layers = int(resolution), int(layers)
        self.image: Image | None = None
        self.layer_views: list[Any] = []
        self.framebuffers: list[Any] = []
        self.samplers: list[Any] = []
        self._previews: dict[int, Any] = {}  # layer -> its grey view (preview_view)
        self.read_layout = getattr(vk, READ_LAYOUT_NAME)
        try:
            self.image = Image(
                device,
                self.resolution,
                self.resolution,
                getattr(vk, SHADOW_FORMAT_NAME),
                vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT,
                vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                layers=self.layers,
            )
            for layer in range(self.layers):
                self.layer_views.append(self.image.layer_view(layer))
                self.framebuffers.append(
                    create_framebuffer(device, render_pass, [self.layer_views[-1]], self.resolution, self.resolution)
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
        layout = self.read_layout
        assert self.image is not None
        view = self.image.view  # the 2D array of every layer
        return [vk.VkDescriptorImageInfo(sampler=s, imageView=view, imageLayout=layout) for s in self.samplers]

    @property
    def plain_sampler(self) -> Any:
        """The nearest sampler that reads depths (no comparison)."""
        return self.samplers[2]

    @property
    def destroyed(self) -> bool:
        return self.image is None

    def preview_view(self, layer: int) -> Any:
        """A 2D view of `layer` whose R, G and B are its depth (A one): a grey image, near
        (reverse-Z: 1) white, far black; read it with plain_sampler in read_layout. Made on first
        use, destroyed with the maps."""
        assert self.image is not None
        if not 0 <= layer < self.layers:
            raise IndexError(f"layer {layer} of {self.layers}")
        view = self._previews.get(layer)
        if view is None:
            vk = self.vk
            r, one = vk.VK_COMPONENT_SWIZZLE_R, vk.VK_COMPONENT_SWIZZLE_ONE
            view = self._previews[layer] = vk.vkCreateImageView(
                self.device.handle,
                vk.VkImageViewCreateInfo(
                    image=self.image.handle,
                    viewType=vk.VK_IMAGE_VIEW_TYPE_2D,
                    format=self.image.format,
                    components=vk.VkComponentMapping(r=r, g=r, b=r, a=one),
                    subresourceRange=vk.VkImageSubresourceRange(
                        aspectMask=vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                        baseMipLevel=0,
                        levelCount=1,
                        baseArrayLayer=layer,
                        layerCount=1,
                    ),
                ),
                None,
            )
        return view

    def destroy(self) -> None:
        vk, handle = self.vk, self.device.handle
        for v in self._previews.values():
            vk.vkDestroyImageView(handle, v, None)
        self._previews = {}
        for sampler in self.samplers:
            vk.vkDestroySampler(handle, sampler, None)
        for fb in self.framebuffers:
            vk.vkDestroyFramebuffer(handle, fb, None)
        for v in self.layer_views:
            vk.vkDestroyImageView(handle, v, None)
        if self.image is not None:
            self.image.destroy()
        self.samplers, self.framebuffers, self.layer_views = [], [], []
        self.image = None
