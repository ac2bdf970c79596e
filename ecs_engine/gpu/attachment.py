"""The attachment description every render pass here writes the same way, and the calls that
make a render pass and a framebuffer."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .device import Device


def attachment(vk: Any, fmt: int, samples: int, load: int, store: int, final: int, initial: int = 0) -> Any:
    """An attachment without stencil, its contents undefined when the pass begins unless loaded
    from `initial` (VK_IMAGE_LAYOUT_UNDEFINED is 0)."""
    return vk.VkAttachmentDescription(
        format=fmt,
        samples=samples,
        loadOp=load,
        storeOp=store,
        stencilLoadOp=vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE,
        stencilStoreOp=vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
        initialLayout=initial,
        finalLayout=final,
    )


def make_render_pass(device: Device, attachments: list[Any], subpasses: list[Any], dependencies: list[Any]) -> Any:
    """A VkRenderPass of these attachments, subpasses and dependencies."""
    vk = device.vk
    return vk.vkCreateRenderPass(
        device.handle,
        vk.VkRenderPassCreateInfo(pAttachments=attachments, pSubpasses=subpasses, pDependencies=dependencies),
        None,
    )


def create_framebuffer(device: Device, render_pass: Any, views: list[Any], width: int, height: int) -> Any:
    vk = device.vk
    device.objects_version += 1
    return vk.vkCreateFramebuffer(
        device.handle,
        vk.VkFramebufferCreateInfo(renderPass=render_pass, pAttachments=views, width=width, height=height, layers=1),
        None,
    )
