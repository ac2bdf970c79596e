"""What a pass records with: its images and buffers by name, and dynamic rendering over the
attachments it declared (load ops and clear values as declared, viewport and scissor set)."""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

from ...errors import UsageError
from .resources import Access, GraphBuffer, GraphImage, Load, Use, is_depth

_INTEGER = ("_UINT", "_SINT")
_TOKEN = object()  # marks a caller's token among the renderings' keys


@dataclass(frozen=True)
class Rendering:
    """One begin_rendering's structs: the VkRenderingInfo's address, the viewport and scissor
    arrays, and what their pointers point to (kept alive with them)."""

    info: Any
    viewport: Any
    scissor: Any
    keep: Any


class PassContext:
    def __init__(
        self,
        device: Any,
        extent: tuple[int, int],
        images: dict[str, GraphImage],
        buffers: dict[str, GraphBuffer],
        format_names: dict[str, str],
        dont_store: frozenset[tuple[str, Use]] = frozenset(),
        made: dict[tuple, Rendering] | None = None,
    ) -> None:
        self.device = device
        self.vk = device.vk
        self.extent = extent
        self._images = images
        self._buffers = buffers
        self._formats = format_names
        self._dont_store = dont_store  # writes whose attachments store nothing (compile.py)
        # begin_rendering's structs by what they were made from (the graph keeps them per compile)
        self._made: dict[tuple, Rendering] = made if made is not None else {}
        self._asked: dict[tuple, Rendering] = {}  # by the arguments alone (this context's images)
        self.pass_name = ""
        self._uses: tuple[Use, ...] = ()
        self._rendering = False
        self._cb: Any = None  # the command buffer of the pass being recorded

    def _enter(self, cb: Any, pass_name: str, uses: tuple[Use, ...]) -> None:
        self._cb, self.pass_name, self._uses = cb, pass_name, uses

    def _leave(self) -> None:
        if self._rendering:
            raise UsageError(f"pass {self.pass_name!r} began rendering and did not end it")

    def image(self, name: str) -> GraphImage:
        found = self._images.get(name)
        if found is None:
            raise UsageError(f"pass {self.pass_name!r} asks for image {name!r}, which the graph does not have")
        return found

    def buffer(self, name: str) -> GraphBuffer:
        found = self._buffers.get(name)
        if found is None:
            raise UsageError(f"pass {self.pass_name!r} asks for buffer {name!r}, which the graph does not have")
        return found

    def _declared(self, name: str, mip: int, layer: int, accesses: tuple[Access, ...]) -> Use:
        for use in self._uses:
            if use.resource == name and use.access in accesses and use.mip in (None, mip):
                if use.layer in (None, layer):
                    return use
        wanted = " or ".join(a.name for a in accesses)
        raise UsageError(
            f"pass {self.pass_name!r} renders to {name!r} (mip {mip}, layer {layer}) without declaring it as {wanted}"
        )

    def _attachment(
        self, name: str, mip: int, layer: int, accesses: tuple[Access, ...], resolve: str | None = None
    ) -> Any:
        vk = self.vk
        use = self._declared(name, mip, layer, accesses)
        image = self.image(name)
        fmt = self._formats[name]
        load = {
            Load.LOAD: vk.VK_ATTACHMENT_LOAD_OP_LOAD,
            Load.CLEAR: vk.VK_ATTACHMENT_LOAD_OP_CLEAR,
            Load.DONT_CARE: vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE,
        }[use.load if use.write else Load.LOAD]
        if is_depth(fmt):
            clear = vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=use.clear[0], stencil=0))
        elif fmt.endswith(_INTEGER):
            kind = "uint32" if fmt.endswith("_UINT") else "int32"
            clear = vk.VkClearValue(color=vk.VkClearColorValue(**{kind: [int(c) for c in use.clear]}))
        else:
            clear = vk.VkClearValue(color=vk.VkClearColorValue(float32=list(use.clear)))
        extra: dict[str, Any] = {}
        if resolve is not None:
            self._declared(resolve, mip, layer, (Access.RESOLVE_WRITE,))
            integer = fmt.endswith(_INTEGER)
            extra = {
                "resolveMode": vk.VK_RESOLVE_MODE_SAMPLE_ZERO_BIT if integer else vk.VK_RESOLVE_MODE_AVERAGE_BIT,
                "resolveImageView": self.image(resolve).attachment_view(mip, layer),
                "resolveImageLayout": vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
            }
        return vk.VkRenderingAttachmentInfo(
            imageView=image.attachment_view(mip, layer),
            imageLayout=getattr(vk, f"VK_IMAGE_LAYOUT_{use.access.usage.layout}"),
            loadOp=load,
            storeOp=self._store_op(use),
            clearValue=clear,
            **extra,
        )

    def _store_op(self, use: Use) -> int:
        vk = self.vk
        if not use.write:  # a read-only depth attachment stores nothing (a store would be a write)
            return int(vk.VK_ATTACHMENT_STORE_OP_NONE)
        if (self.pass_name, use) in self._dont_store:  # nothing later reads it
            return int(vk.VK_ATTACHMENT_STORE_OP_DONT_CARE)
        return int(vk.VK_ATTACHMENT_STORE_OP_STORE)

    def begin_rendering(
        self,
        colors: tuple[str, ...] = (),
        depth: str | None = None,
        resolve: tuple[str | None, ...] | None = None,
        *,
        secondaries: bool = False,
        mip: int = 0,
        layer: int = 0,
        area: tuple[int, int, int, int] | None = None,
        token: Hashable = None,
    ) -> None:
        """vkCmdBeginRendering over these declared attachments at `mip` and array `layer`;
        `resolve[i]` (declared RESOLVE_WRITE) receives colour i resolved. `area` (x, y, w, h):
        the render area (CLEAR clears it only; declare the write `region=True` to keep the
        rest), default the whole attachment. Viewport and scissor are the area (not with
        `secondaries`: those set their own). The structs are made once per pass, attachments'
        views and area (kept until the graph compiles again) and recorded by raw calls.
        `token`: the caller's cheap stand-in for all the arguments and the attachments' views
        (a layer, its size and the image's handle): a rendering made under it is begun again
        without looking at them (a pass beginning many renderings a frame)."""
        if token is not None:
            made = self._made.get((self.pass_name, _TOKEN, token))
            if made is not None and not self._rendering:
                self._begin(made, secondaries)
                return
        colors = (colors,) if isinstance(colors, str) else tuple(colors)
        resolve = tuple(resolve) if resolve is not None else None
        area = tuple(area) if area is not None else None  # type: ignore[assignment]
        if self._rendering:
            raise UsageError(f"pass {self.pass_name!r} begins rendering twice")
        images = self._images
        asked = (self.pass_name, colors, depth, resolve, secondaries, mip, layer, area)
        made = self._asked.get(asked)  # this context's images are fixed: the views need no look
        if made is None:
            try:
                names = (*colors, *(resolve or ()), depth)
                views = tuple(images[n].attachment_view(mip, layer) for n in names if n)
            except KeyError as missing:
                raise UsageError(
                    f"pass {self.pass_name!r} renders to {missing}, which the graph does not have"
                ) from None
            key = (*asked, views)
            made = self._made.get(key)
            if made is None:
                if len(self._made) >= 64:  # imported images come and go (swapchain remakes)
                    self._made.clear()
                made = self._made[key] = self._make(colors, depth, resolve, secondaries, mip, layer, area)
            self._asked[asked] = made
        if token is not None:
            self._made[(self.pass_name, _TOKEN, token)] = made
        self._begin(made, secondaries)

    def render_secondaries(
        self, buffers: Any, token: Hashable, depth: str | None = None, layer: int = 0, area: Any = None
    ) -> None:
        """begin_rendering(depth=, layer=, area=, secondaries=True, token=), `buffers` (secondary
        command buffers, or none) executed, end_rendering: one call per rendering for a pass
        that begins many a frame (the shadow maps' layers), a known token costing one lookup."""
        lib, cb = self.vk.lib, self._cb
        made = None if self._rendering else self._made.get((self.pass_name, _TOKEN, token))
        if made is None:
            self.begin_rendering(depth=depth, layer=layer, area=area, secondaries=True, token=token)
        else:
            lib.vkCmdBeginRendering(cb, made.info)
        if buffers:
            lib.vkCmdExecuteCommands(cb, len(buffers), self.vk.ffi.new("VkCommandBuffer[]", buffers))
        lib.vkCmdEndRendering(cb)
        self._rendering = False

    def _begin(self, made: Rendering, secondaries: bool) -> None:
        lib, cb = self.vk.lib, self._cb
        lib.vkCmdBeginRendering(cb, made.info)
        self._rendering = True
        if not secondaries:
            lib.vkCmdSetViewport(cb, 0, 1, made.viewport)
            lib.vkCmdSetScissor(cb, 0, 1, made.scissor)

    def _make(
        self,
        colors: tuple[str, ...],
        depth: str | None,
        resolve: tuple[str | None, ...] | None,
        secondaries: bool,
        mip: int,
        layer: int,
        area: tuple[int, int, int, int] | None,
    ) -> Rendering:
        vk = self.vk
        if resolve is not None and len(resolve) != len(colors):
            raise UsageError(f"pass {self.pass_name!r}: one resolve target (or None) per colour attachment")
        color_accesses = (Access.COLOR_WRITE, Access.COLOR_READ_WRITE)
        infos = [
            self._attachment(name, mip, layer, color_accesses, resolve[i] if resolve is not None else None)
            for i, name in enumerate(colors)
        ]
        depth_accesses = (Access.DEPTH_WRITE, Access.DEPTH_READ)
        depth_info = self._attachment(depth, mip, layer, depth_accesses) if depth else None
        named = [*colors, *([depth] if depth else [])]
        if not named:
            raise UsageError(f"pass {self.pass_name!r} begins rendering with no attachment")
        x, y, w, h = self._area(named[0], mip, area)
        rect = vk.VkRect2D(offset=vk.VkOffset2D(x, y), extent=vk.VkExtent2D(w, h))
        info = vk.VkRenderingInfo(
            flags=vk.VK_RENDERING_CONTENTS_SECONDARY_COMMAND_BUFFERS_BIT if secondaries else 0,
            renderArea=rect,
            layerCount=1,
            pColorAttachments=infos or None,
            pDepthAttachment=depth_info,
        )
        ffi = vk.ffi
        viewport = ffi.new("VkViewport[1]", [(float(x), float(y), float(w), float(h), 0.0, 1.0)])
        scissor = ffi.new("VkRect2D[1]", [((x, y), (w, h))])
        return Rendering(ffi.addressof(info), viewport, scissor, (info, infos, depth_info))

    def _area(self, name: str, mip: int, area: tuple[int, int, int, int] | None) -> tuple[int, int, int, int]:
        w, h = self.image(name).mip_extent(mip)
        if area is None:
            return (0, 0, w, h)
        x, y, aw, ah = (int(v) for v in area)
        if x < 0 or y < 0 or aw < 1 or ah < 1 or x + aw > w or y + ah > h:
            raise UsageError(f"pass {self.pass_name!r}: render area {area} is not inside {name!r} ({w}x{h})")
        return (x, y, aw, ah)

    def end_rendering(self) -> None:
        if not self._rendering:
            raise UsageError(f"pass {self.pass_name!r} ends rendering it did not begin")
        self.vk.lib.vkCmdEndRendering(self._cb)
        self._rendering = False
