"""The frame's render pass: colour + reverse-Z depth, two subpasses.

Subpass 0 draws the scene (later: only secondary command buffers); subpass 1 draws overlays
recorded inline (light billboards, UI) over the same attachments, depth-tested against the scene.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .device import Device


def create_render_pass(device: Device, color_format: int, final_layout: int) -> Any:
    vk = device.vk
    color = vk.VkAttachmentDescription(
        format=color_format,
        samples=vk.VK_SAMPLE_COUNT_1_BIT,
        loadOp=vk.VK_ATTACHMENT_LOAD_OP_CLEAR,
        storeOp=vk.VK_ATTACHMENT_STORE_OP_STORE,
        stencilLoadOp=vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE,
        stencilStoreOp=vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
        initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
        finalLayout=final_layout,
    )
    depth = vk.VkAttachmentDescription(
        format=vk.VK_FORMAT_D32_SFLOAT,
        samples=vk.VK_SAMPLE_COUNT_1_BIT,
        loadOp=vk.VK_ATTACHMENT_LOAD_OP_CLEAR,
        storeOp=vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
        stencilLoadOp=vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE,
        stencilStoreOp=vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
        initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
        finalLayout=vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    )
    color_ref = vk.VkAttachmentReference(attachment=0, layout=vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL)
    depth_ref = vk.VkAttachmentReference(attachment=1, layout=vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
    subpasses = [
        vk.VkSubpassDescription(
            pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS,
            pColorAttachments=[color_ref],
            pDepthStencilAttachment=depth_ref,
        )
        for _ in range(2)
    ]
    color_stage = vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
    depth_stages = vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
    color_rw = vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT
    depth_rw = vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT
    dependencies = [
        # the previous frame's use of the attachments (or the presentation engine) before the clear
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=0,
            srcStageMask=color_stage | depth_stages,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=0,
            dstAccessMask=color_rw | depth_rw,
        ),
        # scene -> overlay: colour blended on top, depth tested against the scene
        vk.VkSubpassDependency(
            srcSubpass=0,
            dstSubpass=1,
            srcStageMask=color_stage | depth_stages,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
            dstAccessMask=color_rw | depth_rw,
            dependencyFlags=vk.VK_DEPENDENCY_BY_REGION_BIT,
        ),
        # overlay -> whatever reads the colour next (copy for readback, or present)
        vk.VkSubpassDependency(
            srcSubpass=1,
            dstSubpass=vk.VK_SUBPASS_EXTERNAL,
            srcStageMask=color_stage,
            dstStageMask=vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_TRANSFER_READ_BIT,
        ),
    ]
    return vk.vkCreateRenderPass(
        device.handle,
        vk.VkRenderPassCreateInfo(pAttachments=[color, depth], pSubpasses=subpasses, pDependencies=dependencies),
        None,
    )


def create_framebuffer(device: Device, render_pass: Any, views: list[Any], width: int, height: int) -> Any:
    vk = device.vk
    return vk.vkCreateFramebuffer(
        device.handle,
        vk.VkFramebufferCreateInfo(renderPass=render_pass, pAttachments=views, width=width, height=height, layers=1),
        None,
    )
