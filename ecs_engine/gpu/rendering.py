"""Dynamic rendering's structs, built once and called raw: a VkRenderingInfo over attachments
(vkCmdBeginRendering instead of a render pass and framebuffer) and a VkDependencyInfo (what a
render pass's layouts and subpass dependencies did, for vkCmdPipelineBarrier2). Each cffi struct
costs microseconds of Python and a small scene's whole CPU frame is about 100 us: the callers make
these once per set of images and keep the pointers (with what they point to)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .image_barrier import image_barrier

#: (VkImage, aspect mask, old layout, new layout): one image's layout transition in a dependency
Transition = tuple[Any, int, int, int]


@dataclass(frozen=True)
class Attachment:
    """One attachment of a rendering: its view and the layout it is in while drawn, the load and
    store ops' names (LOAD, CLEAR, DONT_CARE / STORE, DONT_CARE), the clear value (a VkClearValue,
    with CLEAR), and the single-sample view an MSAA colour resolves into (AVERAGE) at the end."""

    view: Any
    layout: int
    load: str = "CLEAR"
    store: str = "STORE"
    clear: Any = None
    resolve_view: Any = None


class Rendering:
    """A VkRenderingInfo over `colors` and `depth` in `width` x `height`, whose draws come from
    secondaries (`secondaries`, VK_RENDERING_CONTENTS_SECONDARY_COMMAND_BUFFERS_BIT) or are
    recorded inline; `ptr` is for the raw vkCmdBeginRendering."""

    def __init__(
        self,
        vk: Any,
        width: int,
        height: int,
        colors: Sequence[Attachment],
        depth: Attachment | None = None,
        secondaries: bool = True,
    ) -> None:
        color_layout = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL

        def info(a: Attachment) -> Any:
            resolve = a.resolve_view is not None
            return vk.VkRenderingAttachmentInfo(
                imageView=a.view,
                imageLayout=a.layout,
                resolveMode=vk.VK_RESOLVE_MODE_AVERAGE_BIT if resolve else vk.VK_RESOLVE_MODE_NONE,
                resolveImageView=a.resolve_view if resolve else vk.ffi.NULL,
                resolveImageLayout=color_layout if resolve else vk.VK_IMAGE_LAYOUT_UNDEFINED,
                loadOp=getattr(vk, f"VK_ATTACHMENT_LOAD_OP_{a.load}"),
                storeOp=getattr(vk, f"VK_ATTACHMENT_STORE_OP_{a.store}"),
                clearValue=a.clear if a.clear is not None else vk.VkClearValue(),
            )

        self.colors = [info(a) for a in colors]
        self.depth = info(depth) if depth is not None else None
        self.area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(width, height))
        self.info = vk.VkRenderingInfo(
            flags=vk.VK_RENDERING_CONTENTS_SECONDARY_COMMAND_BUFFERS_BIT if secondaries else 0,
            renderArea=self.area,
            layerCount=1,
            colorAttachmentCount=len(self.colors),
            pColorAttachments=self.colors or vk.ffi.NULL,
            pDepthAttachment=self.depth if self.depth is not None else vk.ffi.NULL,
        )
        self.ptr = vk.ffi.addressof(self.info)


def clear_color(vk: Any, rgba: Sequence[float]) -> Any:
    return vk.VkClearValue(color=vk.VkClearColorValue(float32=list(rgba)))


def clear_depth(vk: Any, depth: float = 0.0) -> Any:
    """0.0 by default: reverse-Z's far plane."""
    return vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=depth, stencil=0))


class Dependency:
    """One VkDependencyInfo for vkCmdPipelineBarrier2, as a render pass's subpass dependency with
    VK_SUBPASS_EXTERNAL was: a memory dependency from (src stages, src accesses) to (dst stages,
    dst accesses) over everything, and `transitions` of the attachments made between the two
    scopes (the render pass's initial and final layouts); `ptr` is for the raw call."""

    def __init__(self, vk: Any, src: tuple[int, int], dst: tuple[int, int], transitions: Sequence[Transition]) -> None:
        self.memory = vk.VkMemoryBarrier2(
            srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1]
        )
        self.images = [
            image_barrier(
                vk,
                image,
                aspect=aspect,
                old=old,
                new=new,
                src_stage=src[0],
                src_access=src[1],
                dst_stage=dst[0],
                dst_access=dst[1],
            )
            for image, aspect, old, new in transitions
        ]
        self.info = vk.VkDependencyInfo(
            memoryBarrierCount=1,
            pMemoryBarriers=[self.memory],
            imageMemoryBarrierCount=len(self.images),
            pImageMemoryBarriers=self.images or vk.ffi.NULL,
        )
        self.ptr = vk.ffi.addressof(self.info)

    def record(self, cb: Any, lib: Any) -> None:
        lib.vkCmdPipelineBarrier2(cb, self.ptr)
