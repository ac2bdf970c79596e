"""The scene's dynamic renderings (gpu/rendering.py Rendering) over a target's attachments
(gpu/render_pass.py's SceneAttachments), with their clears, made once per set of images and
size (output_passes.py keeps them per output), and the barriers around them
(scene_barriers.py)."""

from __future__ import annotations

from typing import Any

from ..gpu.rendering import Attachment, Rendering, clear_color, clear_depth
from .layouts import NO_MATERIAL
from .scene_barriers import gbuffer_barriers


def gbuffer_rendering(
    vk: Any, attachments: Any, width: int, height: int, background: tuple[float, float, float], begin: Any
) -> tuple[Any, Any, Any, Any]:
    """(Rendering, barrier before, barrier after, `begin`: its secondaries' begin info) of the
    G-buffer: depth cleared to far, the HDR colour to the background, normal-roughness and
    base-metallic to zero, the material index to NO_MATERIAL, all stored."""
    color = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    zero = clear_color(vk, (0.0, 0.0, 0.0, 0.0))
    none = vk.VkClearValue(color=vk.VkClearColorValue(uint32=[NO_MATERIAL, 0, 0, 0]))
    depth, hdr = attachments.images[0], attachments.images[1]
    gbuffer = attachments.gbuffer.images
    colors = [Attachment(hdr.view, color, clear=clear_color(vk, (*background, 1.0)))]
    colors += [Attachment(i.view, color, clear=value) for i, value in zip(gbuffer, (zero, zero, none), strict=True)]
    depth_layout = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL
    depth_attachment = Attachment(depth.view, depth_layout, clear=clear_depth(vk))
    rendering = Rendering(vk, width, height, colors, depth_attachment)
    before, after = gbuffer_barriers(vk, depth.handle, [hdr.handle, *(image.handle for image in gbuffer)])
    return rendering, before, after, begin
