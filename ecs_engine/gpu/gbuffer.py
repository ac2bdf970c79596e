"""The deferred form's first render pass: the opaque meshes write what lighting needs per pixel
(a G-buffer) instead of lighting themselves; a compute pass (render/deferred_pass.py) then lights
every pixel and adds into the HDR colour, and the target's render pass (gpu/render_pass.py,
form "deferred") loads depth and HDR colour for the set-aside rows, billboards and tone map.

Why: on the H100 a fragment shader runs on the few graphics-capable units of the chip, a compute
shader on all of it; thousands of lights cost the forward frame 4x the 6-light one
(docs/performance.md).

Attachments, one subpass:
0. depth (reverse-Z), kept for the lighting pass and the second render pass;
1. the HDR colour: ambient, emissive and unlit materials (the lighting pass adds the lights);
2. normal xyz (unit, render-origin space) and roughness, RGBA16F;
3. base colour rgb (linear, after its texture) and metallic, RGBA16F;
4. the material index, R32_UINT (NO_MATERIAL, render/layouts.py, where no lit surface is:
   background, unlit materials).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .attachment import attachment, create_framebuffer, make_render_pass
from .memory import Image

if TYPE_CHECKING:
    from .device import Device

GBUFFER_FORMAT_NAMES = ("VK_FORMAT_R32G32B32A32_SFLOAT", "VK_FORMAT_R16G16B16A16_SFLOAT", "VK_FORMAT_R32_UINT")
GBUFFER_COLORS = 1 + len(GBUFFER_FORMAT_NAMES)  # the mesh pipelines' colour attachments here


def create_gbuffer_pass(device: Device, depth_format: int, hdr_format: int) -> Any:
    vk = device.vk
    general = vk.VK_IMAGE_LAYOUT_GENERAL
    color_layout = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    depth_layout = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL

    def cleared(fmt: int, final: int) -> Any:
        return attachment(vk, fmt, 1, vk.VK_ATTACHMENT_LOAD_OP_CLEAR, vk.VK_ATTACHMENT_STORE_OP_STORE, final)

    attachments = [
        cleared(depth_format, vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL),  # sampled by the lighting
        cleared(hdr_format, general),  # read and written by the lighting as a storage image
        *(cleared(getattr(vk, name), general) for name in GBUFFER_FORMAT_NAMES),
    ]
    ref = vk.VkAttachmentReference
    subpass = vk.VkSubpassDescription(
        pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS,
        pColorAttachments=[ref(attachment=i, layout=color_layout) for i in range(1, 1 + GBUFFER_COLORS)],
        pDepthStencilAttachment=ref(attachment=0, layout=depth_layout),
    )
    color_stage = vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
    depth_stages = vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
    compute = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
    color_write = vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT
    depth_write = vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
    color_rw = color_write | vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT
    depth_rw = depth_write | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT
    dependencies = [
        # the previous frame's lighting, second pass and tone map used these images (frames in
        # flight share them) before this frame clears them
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=0,
            srcStageMask=color_stage | depth_stages | compute | vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=color_write | depth_write | vk.VK_ACCESS_SHADER_WRITE_BIT,
            dstAccessMask=color_rw | depth_rw,
        ),
        # the G-buffer, depth and HDR colour -> the lighting's reads (and its HDR writes)
        vk.VkSubpassDependency(
            srcSubpass=0,
            dstSubpass=vk.VK_SUBPASS_EXTERNAL,
            srcStageMask=color_stage | depth_stages,
            dstStageMask=compute,
            srcAccessMask=color_write | depth_write,
            dstAccessMask=vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT,
        ),
    ]
    return make_render_pass(device, attachments, [subpass], dependencies)


class GBuffer:
    """The G-buffer images (normal, base colour, material) of one size and the first pass's
    framebuffer over depth, HDR colour and them."""

    def __init__(self, device: Device, render_pass: Any, depth_view: Any, hdr_view: Any, width: int, height: int):
        vk = device.vk
        self.device = device
        self.images: list[Image] = []
        self.framebuffer = None
        usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_STORAGE_BIT
        try:
            for name in GBUFFER_FORMAT_NAMES:
                self.images.append(Image(device, width, height, getattr(vk, name), usage, vk.VK_IMAGE_ASPECT_COLOR_BIT))
            views = [depth_view, hdr_view, *(image.view for image in self.images)]
            self.framebuffer = create_framebuffer(device, render_pass, views, width, height)
        except BaseException:
            self.destroy()
            raise

    @property
    def views(self) -> list[Any]:
        """Normal-roughness, base-metallic, material."""
        return [image.view for image in self.images]

    def destroy(self) -> None:
        if self.framebuffer is not None:
            self.device.vk.vkDestroyFramebuffer(self.device.handle, self.framebuffer, None)
            self.framebuffer = None
        for image in self.images:
            image.destroy()
        self.images = []
