"""Render to texture: a camera's finished image copied into the texture layer materials sample.

Usage (a view's graph, for a camera with `RenderTexture(name, width, height)`):

    handle = materials(world).textures.render_target(name, width, height)  # before the frame's
    # texture sync (Renderer._sync_textures), so its layer exists; the same handle every frame
    image = RenderTargetImage(device, width, height)  # kept per name, destroyed with the view
    image.import_into(graph, "target")                # each frame (a new handle recompiles nothing)
    ... the view's passes draw "target" as the window's graph does (forward, tone_map, post) ...
    graph.add_pass(RenderTexturePass(renderer.texture_pages, handle, source="target"))
    # after tone mapping and post effects, in place of the readback pass; a side effect that
    # reads "target": it and the passes drawing "target" are kept without a graph.output().
    # Several render textures in one graph: give each pass its own name= ("render_texture:tv").

`RenderTargetImage` is RGBA8 sRGB (VK_FORMAT_R8G8B8A8_SRGB, the window's format: pipelines made
for the window draw into it), with COLOR_ATTACHMENT, TRANSFER_SRC and SAMPLED usage. Draw the view
at `width` x `height` with the aspect width / height (ViewData.rect); the pass scales it into the
square layer (size_class's side), and a material stretched over a width:height quad shows it
undistorted. Record the view's graph before the graphs whose passes sample the texture (the
window's), in the same command buffer or an earlier submission: the pass's last barrier makes the
layer visible to fragment and compute shaders after it.

What the pass records: the layer (all its mips) from SHADER_READ_ONLY (the previous frame's
sampling) to TRANSFER_DST; a blit of "target" into mip 0 (linear: the layer is stored as sRGB,
gpu/array_image.py, so blits filter in linear light as the CPU's mip_chain does); each mip blitted
from the one above (that one moved to TRANSFER_SRC first); then every mip back to
SHADER_READ_ONLY. Where the device cannot blit that format (none we know of: blits with linear
filtering of R8G8B8A8_SRGB are required by Vulkan), it falls back to a nearest-filtered blit, or
to a copy of mip 0 alone (the camera's image must then be the layer's size; the lower mips keep
what they held). The page image is owned by TexturePages, not by the graph: these barriers are
the pass's own, over its one layer. `key()` names the page's image, the layer and the upload
generation, so frame replay records again when a sync remakes the page.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

from ...errors import UsageError
from ...gpu.functions import handle_int
from ...gpu.image_barrier import image_barrier
from ...gpu.memory import Image
from ..assets.texture_pages import TexturePages, TexturePlace
from ..graph import Access, FrameGraph, Pass, PassBuilder, PassContext

__all__ = ["RenderTargetImage", "RenderTexturePass", "blit_filter"]

#: one command of the pass, its structs made: called with (vk.lib, the command buffer)
Step = Callable[[Any, Any], None]


class RenderTargetImage:
    """The image a render-texture view is drawn into: `width` x `height` RGBA8 sRGB, one mip."""

    def __init__(self, device: Any, width: int, height: int) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height = int(width), int(height)
        self.format = vk.VK_FORMAT_R8G8B8A8_SRGB
        usage = (
            vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
        )
        self.image = Image(device, self.width, self.height, self.format, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT)

    @property
    def handle(self) -> Any:
        return self.image.handle

    @property
    def view(self) -> Any:
        return self.image.view

    def import_into(self, graph: FrameGraph, name: str = "target") -> None:
        """Import it into `graph` as `name`: its old pixels discarded (the view draws every one),
        left in TRANSFER_SRC (RenderTexturePass reads it last); its first barrier waits for the
        previous frame's drawing and copy of it."""
        graph.import_image(
            name,
            handle=self.handle,
            view=self.view,
            format=self.format,
            extent=(self.width, self.height),
            layout_before="UNDEFINED",
            layout_after="TRANSFER_SRC_OPTIMAL",
            stage_before=("COLOR_ATTACHMENT_OUTPUT", "ALL_TRANSFER"),
        )

    def destroy(self) -> None:
        self.image.destroy()


def blit_filter(device: Any, *formats: int) -> int | None:
    """VK_FILTER_LINEAR where every format can be blitted from and to with linear filtering,
    VK_FILTER_NEAREST where only blits, None where not even those (optimal tiling)."""
    vk = device.vk
    blits = vk.VK_FORMAT_FEATURE_BLIT_SRC_BIT | vk.VK_FORMAT_FEATURE_BLIT_DST_BIT
    linear = True
    for fmt in formats:
        features = vk.vkGetPhysicalDeviceFormatProperties(device.physical, fmt).optimalTilingFeatures
        if features & blits != blits:
            return None
        linear = linear and bool(features & vk.VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT)
    return vk.VK_FILTER_LINEAR if linear else vk.VK_FILTER_NEAREST


class RenderTexturePass(Pass):
    """Copies graph image `source` into texture `handle`'s layer of `pages` and makes its mips."""

    def __init__(self, pages: TexturePages, handle: int, source: str = "target", name: str = "render_texture") -> None:
        self.pages, self.handle, self.source, self.name = pages, int(handle), source, name
        self._filters: dict[int, int | None] = {}  # source format -> blit_filter with the page's
        self._steps: tuple[tuple, list[Step]] | None = None  # (what they were made for, the steps)

    def setup(self, builder: PassBuilder) -> None:
        builder.read(self.source, Access.TRANSFER_READ)
        builder.side_effect()  # writes the page, outside the graph

    def _place(self) -> TexturePlace:
        if self.handle not in self.pages.render_targets:  # a texture with pixels of its own: never drawn over
            raise UsageError(f"texture {self.handle} is not a render target (Textures.render_target makes them)")
        return self.pages.place(self.handle)

    def key(self) -> Hashable:
        place = self._place()
        return (place.generation, handle_int(self.pages.device.vk, place.image.handle), place.layer, place.side)

    def record(self, cb: Any, ctx: PassContext) -> None:
        place = self._place()
        src = ctx.image(self.source)
        made_for = (place.generation, place.layer, handle_int(ctx.vk, src.handle), src.extent, src.format)
        if self._steps is None or self._steps[0] != made_for:
            self._steps = (made_for, self._plan(ctx.device, place, src.handle, src.extent, src.format))
        lib = ctx.vk.lib  # raw calls with structs made once: the wrappers cost about 2 ms a frame
        for step in self._steps[1]:
            step(lib, cb)

    def _plan(self, device: Any, place: TexturePlace, src: Any, extent: tuple[int, int], fmt: int) -> list[Step]:
        """The steps recording the copy: barriers, blits (or the one copy), with their structs."""
        vk = device.vk
        if fmt not in self._filters:
            self._filters[fmt] = blit_filter(device, fmt, place.image.format)
        blit = self._filters[fmt]
        if blit is None and extent != (place.side, place.side):
            raise UsageError(
                f"render texture {self.handle}: the device cannot blit {extent[0]} x {extent[1]} pixels into "
                f"its {place.side} x {place.side} layer; draw the view at {place.side} x {place.side}"
            )
        read_only, dst, src_layout = (
            vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
            vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
            vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
        )
        barriers = _Barriers(device, place)
        steps = [barriers.step([barriers.make(0, place.mips, read_only, dst)])]
        if blit is None:
            steps.append(_copy(vk, src, place, extent))
            steps.append(barriers.step([barriers.make(0, place.mips, dst, read_only)]))
            return steps
        steps.append(_blit(vk, (src, 0, 0), extent, place, 0, blit))
        for mip in range(1, place.mips):
            steps.append(barriers.step([barriers.make(mip - 1, 1, dst, src_layout)]))
            steps.append(_blit(vk, (place.image.handle, mip - 1, place.layer), _side(place, mip - 1), place, mip, blit))
        last = place.mips - 1
        finals = [barriers.make(last, 1, dst, read_only)]
        if last:
            finals.insert(0, barriers.make(0, last, src_layout, read_only))
        steps.append(barriers.step(finals))
        return steps


def _side(place: TexturePlace, mip: int) -> tuple[int, int]:
    side = max(place.side >> mip, 1)
    return side, side


def _layers(vk: Any, mip: int, layer: int) -> Any:
    color = vk.VK_IMAGE_ASPECT_COLOR_BIT
    return vk.VkImageSubresourceLayers(aspectMask=color, mipLevel=mip, baseArrayLayer=layer, layerCount=1)


def _blit(
    vk: Any, src: tuple[Any, int, int], extent: tuple[int, int], place: TexturePlace, mip: int, blit: int
) -> Step:
    """`src` (image, mip, layer: the camera's image, or the layer's mip above), its whole
    `extent`, into the layer's `mip`."""
    dw, dh = _side(place, mip)
    region = vk.VkImageBlit(
        srcSubresource=_layers(vk, src[1], src[2]),
        srcOffsets=[vk.VkOffset3D(0, 0, 0), vk.VkOffset3D(extent[0], extent[1], 1)],
        dstSubresource=_layers(vk, mip, place.layer),
        dstOffsets=[vk.VkOffset3D(0, 0, 0), vk.VkOffset3D(dw, dh, 1)],
    )
    pointer, image, dst = vk.ffi.addressof(region), src[0], place.image.handle
    from_layout, to_layout = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL

    def step(lib: Any, cb: Any, keep: Any = region) -> None:  # holds `region`: the pointer does not
        lib.vkCmdBlitImage(cb, image, from_layout, dst, to_layout, 1, pointer, blit)

    return step


def _copy(vk: Any, src: Any, place: TexturePlace, extent: tuple[int, int]) -> Step:
    """Mip 0 copied as it is (sRGB bytes into the page's sRGB storage)."""
    region = vk.VkImageCopy(
        srcSubresource=_layers(vk, 0, 0),
        srcOffset=vk.VkOffset3D(0, 0, 0),
        dstSubresource=_layers(vk, 0, place.layer),
        dstOffset=vk.VkOffset3D(0, 0, 0),
        extent=vk.VkExtent3D(extent[0], extent[1], 1),
    )
    pointer, dst = vk.ffi.addressof(region), place.image.handle
    from_layout, to_layout = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL

    def step(lib: Any, cb: Any, keep: Any = region) -> None:  # holds `region`: the pointer does not
        lib.vkCmdCopyImage(cb, src, from_layout, dst, to_layout, 1, pointer)

    return step


class _Barriers:
    """Layout transitions of mips of the place's one layer, with the stages and accesses each
    transition's old and new layout imply (synchronization2)."""

    def __init__(self, device: Any, place: TexturePlace) -> None:
        vk = self.vk = device.vk
        self.place = place
        shaders = vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT
        if device.features.get("rayTracing"):  # ray tracing shaders may sample materials too
            shaders |= vk.VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR
        transfer = vk.VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT
        # layout -> (stages, accesses) as the source of a barrier, then as its destination: the
        # sampling before needs no access made available (a read), only to be waited for
        self.src = {
            vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL: (shaders, vk.VK_ACCESS_2_NONE),
            vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL: (transfer, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT),
            vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL: (transfer, vk.VK_ACCESS_2_NONE),
        }
        self.dst = {
            vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL: (shaders, vk.VK_ACCESS_2_SHADER_SAMPLED_READ_BIT),
            vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL: (transfer, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT),
            vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL: (transfer, vk.VK_ACCESS_2_TRANSFER_READ_BIT),
        }

    def make(self, mip: int, count: int, old: int, new: int) -> Any:
        vk = self.vk
        (src_stages, src_access), (dst_stages, dst_access) = self.src[old], self.dst[new]
        return image_barrier(
            vk,
            self.place.image.handle,
            aspect=vk.VK_IMAGE_ASPECT_COLOR_BIT,
            base_mip=mip,
            mips=count,
            base_layer=self.place.layer,
            old=old,
            new=new,
            src_stage=src_stages,
            src_access=src_access,
            dst_stage=dst_stages,
            dst_access=dst_access,
        )

    def step(self, barriers: list[Any]) -> Step:
        info = self.vk.VkDependencyInfo(pImageMemoryBarriers=barriers)  # keeps the barriers alive
        pointer = self.vk.ffi.addressof(info)

        def step(lib: Any, cb: Any, keep: Any = info) -> None:  # holds `info`: the pointer does not
            lib.vkCmdPipelineBarrier2(cb, pointer)

        return step
