"""The scene's dynamic renderings (gpu/rendering.py Rendering) over a target's attachments
(gpu/scene_attachments.py's SceneAttachments), with their clears, made once per set of images and
size (output_passes.py keeps them per output), and the barriers around them
(scene_barriers.py)."""

from __future__ import annotations

from typing import Any

from ...gpu.gbuffer import gbuffer_formats
from ...gpu.rendering import Attachment, Rendering, clear_color, clear_depth
from ..draw.path import TargetState
from ..layouts import NO_MATERIAL
from .scene_barriers import gbuffer_barriers, overlay_barrier, scene_barriers


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


def scene_rendering(
    vk: Any,
    form: str,
    attachments: Any,
    width: int,
    height: int,
    background: tuple[float, float, float],
    target_view: Any = None,
) -> Rendering:
    """The scene's rendering in a target's `form` (gpu/scene_attachments.py's FORMS), its draws from
    secondaries: hdr, the HDR colour (multisampled with MSAA, then not stored but resolved into
    the single-sample one) and depth cleared, both stored without MSAA (the post effects read
    them); deferred, both loaded (the G-buffer pass and the lighting wrote them) and stored;
    direct, the target image (`target_view`) cleared and stored, depth cleared and not stored."""
    color, depth_layout = (
        vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
        vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    )
    sky = clear_color(vk, (*background, 1.0))
    images = attachments.images  # depth, then the HDR colour (MSAA: multisampled, then its resolve)
    if form == "direct":
        return Rendering(
            vk,
            width,
            height,
            [Attachment(target_view, color, clear=sky)],
            Attachment(images[0].view, depth_layout, store="DONT_CARE", clear=clear_depth(vk)),
        )
    if form == "deferred":
        load = dict(load="LOAD", store="STORE")
        return Rendering(
            vk,
            width,
            height,
            [Attachment(images[1].view, color, **load)],
            Attachment(images[0].view, depth_layout, **load),
        )
    msaa = attachments.samples > 1
    store = "DONT_CARE" if msaa else "STORE"
    hdr = Attachment(images[1].view, color, store=store, clear=sky, resolve_view=images[2].view if msaa else None)
    return Rendering(
        vk, width, height, [hdr], Attachment(images[0].view, depth_layout, store=store, clear=clear_depth(vk))
    )


def overlay_rendering(vk: Any, target_view: Any, width: int, height: int) -> Rendering:
    """The direct form's overlay (the editor's ImGui) over the scene in the target: loaded and
    stored, drawn inline, no depth."""
    color = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    return Rendering(vk, width, height, [Attachment(target_view, color, load="LOAD")], secondaries=False)


def scene_state(
    vk: Any, target: Any, output: Any, width: int, height: int, background: tuple[float, float, float], secondaries: Any
) -> tuple[TargetState, Any]:
    """(TargetState, the scene rendering's AttachmentFormats) for drawing into `output` (one of
    the target's images: output_image) in the target's current form at this size: the scene's
    rendering and barriers, the direct form's overlay rendering, the deferred form's G-buffer
    rendering, and the begin infos their secondaries inherit the formats from."""
    form, attachments = target.form, target.attachments
    formats = target.formats(vk)
    begin = secondaries.begin_info_rendering(formats)
    image, view = target.output_image(output)
    direct = form == "direct"
    rendering = scene_rendering(vk, form, attachments, width, height, background, view if direct else None)
    before, after = scene_barriers(vk, form, attachments, image, target.final_layout)
    overlay = (overlay_barrier(vk), overlay_rendering(vk, view, width, height)) if direct else None
    gbuffer = None
    if form == "deferred":
        gbuffer_begin = secondaries.begin_info_rendering(gbuffer_formats(vk))
        gbuffer = gbuffer_rendering(vk, attachments, width, height, background, gbuffer_begin)
    named = view if direct else attachments.images[-1].view  # what the state draws into, by address
    key = (int(vk.ffi.cast("uintptr_t", named)), width, height)
    scene = (rendering, before, after, overlay)
    return TargetState.make(vk, key, output, scene, begin, background, gbuffer), formats
