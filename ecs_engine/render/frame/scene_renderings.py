"""The deferred form's G-buffer rendering (gpu/rendering.py Rendering) over a target's attachments
(gpu/scene_attachments.py's SceneAttachments), with its clears, made once per set of images and
size (output_passes.py keeps them per output), and the barriers around it (scene_barriers.py);
the scene's own rendering is the output graph's (render/passes/forward.py)."""

from __future__ import annotations

from typing import Any

from ...gpu.gbuffer import gbuffer_formats
from ...gpu.rendering import Attachment, Rendering, clear_color, clear_depth
from ..draw.path import TargetState
from ..layouts import NO_MATERIAL
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


def scene_state(
    vk: Any, target: Any, output: Any, width: int, height: int, background: tuple[float, float, float], secondaries: Any
) -> tuple[TargetState, Any]:
    """(TargetState, the scene rendering's AttachmentFormats) for drawing into `output` (one of
    the target's images: output_image) in the target's current form at this size: the deferred
    form's G-buffer rendering, and the begin infos the secondaries inherit the formats from (the
    scene's rendering itself is the output graph's forward pass: render/passes/forward.py)."""
    form, attachments = target.form, target.attachments
    formats = target.formats(vk)
    begin = secondaries.begin_info_rendering(formats)
    _, view = target.output_image(output)
    direct = form == "direct"
    gbuffer = None
    if form == "deferred":
        gbuffer_begin = secondaries.begin_info_rendering(gbuffer_formats(vk))
        gbuffer = gbuffer_rendering(vk, attachments, width, height, background, gbuffer_begin)
    named = view if direct else attachments.images[-1].view  # what the state draws into, by address
    key = (int(vk.ffi.cast("uintptr_t", named)), width, height)
    return TargetState.make(vk, key, output, begin, background, gbuffer), formats
