"""The output passes' ldr stage (render/frame/output_passes.py): with post effects of the "ldr" stage
on (post/registry.py: FXAA), the output is a small frame graph instead of one rendering:

    tone_map   HDR colour -> "ldr_0" (a transient of the target's format)
    <effect i> "ldr_i" -> "ldr_i+1", the last one -> "target"
    imgui      the overlay over "target" (loaded: drawn on top)

"target" is the target's image for this frame, imported with its old contents discarded
(UNDEFINED) and left as a colour attachment, which output_barriers.py's `after` takes to its
final layout (readback or present) as in the frame without the graph; the graph places every
barrier between them, and the intermediates are its transients (made again only when the size,
the format or the effects change). Each effect adds its own passes (`effect.add(graph, source,
target, create)`), so the graph is made again when the effects change.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

from ..graph import Access, FrameGraph, ImageDesc, Load, Pass
from ..graph.resources import format_name


class _Frame:
    """What this frame's passes draw with (set before each execute)."""

    state: Any = None
    tone_map: tuple[str, float] = ("clamp", 0.0)
    overlay: Any = None
    slot: int = 0


class ToneMapInto(Pass):
    """The output's tone map (tone_map.py's pass, owned by the output passes) into `image`."""

    name = "tone_map"

    def __init__(self, output: Any, frame: _Frame, image: str, desc: ImageDesc) -> None:
        self.output, self.frame, self.image, self.desc = output, frame, image, desc

    def setup(self, builder: Any) -> None:
        builder.create(self.image, self.desc)
        builder.read("hdr", Access.FRAGMENT_SAMPLED)
        builder.write(self.image, Access.COLOR_WRITE)

    def record(self, cb: Any, ctx: Any) -> None:
        ctx.begin_rendering(colors=(self.image,))
        self.output.tone_map_pass.record(cb, self.frame.state, self.output.target, *self.frame.tone_map)
        ctx.end_rendering()

    def key(self) -> Hashable:
        return self.frame.tone_map


class OverlayOver(Pass):
    """The UI over the finished target (loaded, blended over it); nothing without an overlay."""

    name = "imgui"

    def __init__(self, frame: _Frame) -> None:
        self.frame = frame

    def setup(self, builder: Any) -> None:
        builder.write("target", Access.COLOR_READ_WRITE, load=Load.LOAD)

    def record(self, cb: Any, ctx: Any) -> None:
        overlay = self.frame.overlay
        if overlay is None:
            return
        width, height = ctx.extent
        ctx.begin_rendering(colors=("target",))
        overlay.record(cb, self.frame.slot, width, height)
        ctx.end_rendering()


class LdrOutput:
    """The graph of the tone map, the ldr effects and the overlay for one list of effects."""

    def __init__(self, output: Any, effects: list[Any]) -> None:
        self.output, self.effects = output, list(effects)
        self.frame = _Frame()
        self.graph: FrameGraph | None = None
        self._format: int | None = None

    def _make(self, color_format: int) -> FrameGraph:
        device = self.output.device
        graph = FrameGraph(device)
        try:
            desc = ImageDesc(format=f"VK_FORMAT_{format_name(device.vk, color_format)}")
            names = [f"ldr_{i}" for i in range(len(self.effects))] + ["target"]
            graph.add_pass(ToneMapInto(self.output, self.frame, names[0], desc))
            for i, effect in enumerate(self.effects):
                effect.add(graph, names[i], names[i + 1], None if names[i + 1] == "target" else desc)
            graph.add_pass(OverlayOver(self.frame))
            graph.output("target")
        except BaseException:
            graph.destroy()
            raise
        return graph

    def record(
        self,
        cb: Any,
        state: Any,
        rendering: Any,
        tone_map: tuple[str, float],
        overlay: Any,
        slot: int,
        mark: Callable[[str], None] | None,
    ) -> None:
        """This frame's output: `rendering` (output_passes.OutputRendering) names the target's image."""
        target = self.output.target
        hdr = target.hdr_image
        if self.graph is None or self._format != int(target.color_format):
            self.destroy()
            self.graph, self._format = self._make(int(target.color_format)), int(target.color_format)
        graph = self.graph
        extent = (int(state.area.extent.width), int(state.area.extent.height))
        read = "SHADER_READ_ONLY_OPTIMAL"  # as the scene's pass and the hdr effects leave it
        graph.import_image(
            "hdr",
            handle=hdr.handle,
            view=hdr.view,
            format=hdr.format,
            extent=(int(hdr.width), int(hdr.height)),
            layout_before=read,
            layout_after=read,
        )
        self._import_target(graph, rendering, extent)
        frame = self.frame
        frame.state, frame.tone_map, frame.overlay, frame.slot = state, tone_map, overlay, slot
        graph.compile(extent)
        graph.execute(cb)
        # to the final layout by the output's own barrier: the graph's for present would end in
        # no stage, which the swapchain's readback barrier (from colour output) cannot follow
        rendering.barriers.after(self.output.vk.lib, cb)
        frame.state = frame.overlay = None
        if mark is not None:
            mark("tone map, post effects and imgui" if overlay is not None else "tone map and post effects")

    def _import_target(self, graph: FrameGraph, rendering: Any, extent: tuple[int, int]) -> None:
        """The target's image, imported with its format's value (FXAA's pipeline is made for it)."""
        graph.import_image(
            "target",
            handle=rendering.image,
            view=rendering.view,
            format=self.output.target.color_format,
            extent=extent,
            layout_before="UNDEFINED",  # every pixel is written: the old contents go
            layout_after="COLOR_ATTACHMENT_OPTIMAL",  # then OutputBarriers.after, as without the graph
        )

    def describe(self) -> str:
        return self.graph.describe() if self.graph is not None and self.graph.compiled is not None else ""

    def destroy(self) -> None:
        """The graph and the passes it holds (the effects' passes too; not the effects)."""
        if self.graph is not None:
            self.graph.destroy()
            self.graph = None
