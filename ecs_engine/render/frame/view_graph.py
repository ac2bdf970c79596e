"""The output graph of one camera view of several (views.py): the output graph of the window's
one camera (render/passes/output_graph.py) with the passes that write the target placed in the
view's rectangle of it.

Each view draws its scene as a frame of its own size: the graph's extent is the rectangle's, so
the scene's images (the HDR colour and depth imported at that size, every transient, the light
clusters, the G-buffer and its lighting) hold the view's picture from their corner, as they hold
the window's picture at that size. Only what writes "target" is moved:

    clear_target  the first view's: the whole target cleared to the background (what no view
                  covers), its old contents gone (imported UNDEFINED)
    tone_map      "hdr" -> the view's rectangle of "target" (the render area and viewport are the
                  rectangle; the shader reads the HDR colour from its corner: tonemap.frag's
                  offset), a region write: the rest of the target is kept
    imgui         the overlay over the whole target (the last view's frame only carries one)

With post effects after the tone map (FXAA), the tone map writes the graph's own image at the
view's size as for the window, and the last effect writes the rectangle instead (fxaa.py's
`place`: its render area and the offset its shader reads from).

"target" is imported at the target's size; a view after the first loads what the views before
drew (COLOR_ATTACHMENT_OPTIMAL, as the view before left it: its final barrier reaches every later
command, which this view's first barrier chains with); the last view leaves it in the target's
final layout and carries the readback. The direct form has no HDR colour to draw from: several
views draw in the hdr form at least (target_forms.py).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

from ...errors import UsageError
from ..config import Form
from ..graph import Access, FrameGraph, Load, Pass
from ..passes.output_frame import OverlayOver
from ..passes.output_graph import OutputGraph, _final_layout

ATTACHMENT = "COLOR_ATTACHMENT_OPTIMAL"  # the target between the views' frames


@dataclass(frozen=True)
class Placement:
    """Where this frame's view draws: `rect` (x, y, width, height) pixels of a target of `size`;
    `last`: the frame's last view (the target's final layout, the readback); `camera`: its entity."""

    rect: tuple[int, int, int, int]
    size: tuple[int, int]
    last: bool
    camera: int


class ClearTarget(Pass):
    """The whole target cleared to the background before the first view draws."""

    name = "clear_target"

    def __init__(self, frame: Any) -> None:
        self.frame = frame

    def setup(self, builder: Any) -> None:
        builder.write("target", Access.COLOR_WRITE, load=Load.CLEAR, clear=(*self.frame.background, 1.0))

    def declares(self) -> Hashable:
        return self.frame.background

    def record(self, cb: Any, ctx: Any) -> None:
        ctx.begin_rendering(colors=("target",))
        ctx.end_rendering()


class ToneMapView(Pass):
    """The tone map into the view's rectangle of the target (see the module)."""

    name = "tone_map"

    def __init__(self, output: Any, frame: Any, view: ViewGraph) -> None:
        self.output, self.frame, self.view = output, frame, view

    def setup(self, builder: Any) -> None:
        builder.read("hdr", Access.FRAGMENT_SAMPLED)
        builder.write("target", Access.COLOR_WRITE, region=True)  # every pixel of the rectangle

    def declares(self) -> Hashable:
        return ()  # the same every frame

    def record(self, cb: Any, ctx: Any) -> None:
        rect = self.view.placement.rect
        ctx.begin_rendering(colors=("target",), area=rect)
        frame = self.frame
        self.output.tone_map_pass.record(cb, frame.state, self.output.target, *frame.tone_map, offset=rect[:2])
        ctx.end_rendering()

    def key(self) -> Hashable:
        """Its operator and where it draws, and whose picture (a slot never replays another
        view's frame: render/frame/replay.py)."""
        placement = self.view.placement
        return (self.frame.tone_map, placement.rect, placement.camera)


class ViewGraph(OutputGraph):
    """The output graphs of the views' frames at one place in the drawing order (`first`: the
    frame that clears the target); `placement` is set before each frame."""

    def __init__(self, output: Any, first: bool, effects: list[Any]) -> None:
        super().__init__(output, effects)
        self.first = first
        self.placement = Placement((0, 0, 1, 1), (1, 1), True, -1)

    def _make(self, form: Form, samples: int, color_format: int, ray: bool, oit: bool, post: Any) -> FrameGraph:
        if form == Form.DIRECT:
            raise RuntimeError("several camera views draw through the HDR colour (target_forms.py)")
        graph = super()._make(form, samples, color_format, ray, oit, post)
        try:
            graph.remove_pass("imgui").destroy()
            if self.effects:  # the tone map writes its own image; the last effect writes the target
                last = [p for p in graph.passes if getattr(p, "target", None) == "target" and hasattr(p, "place")]
                if not last:
                    raise UsageError("the last post effect after the tone map cannot draw into a camera view's part")
                last[0].place = lambda: self.placement.rect  # (fxaa.py: its area and offset)
                if self.first:
                    graph.add_pass(ClearTarget(self.frame), before=last[0].name)
            else:
                graph.remove_pass("tone_map").destroy()
                if self.first:
                    graph.add_pass(ClearTarget(self.frame))
                graph.add_pass(ToneMapView(self.output, self.frame, self))
            graph.add_pass(OverlayOver(self.frame))  # after the view's passes: over the whole target
        except BaseException:
            graph.destroy()
            raise
        return graph

    def _inputs(self, state: Any, overlay: Any) -> tuple:
        # the view's placement: the imports' sizes and layouts, the readback's place
        return (*super()._inputs(state, overlay), self.placement)

    def _place_readback(self, graph: FrameGraph, wanted: bool) -> None:
        super()._place_readback(graph, wanted and self.placement.last)

    def _attachments_extent(self) -> tuple[int, int]:
        """The HDR colour and depth at the view's size: its picture is drawn from their corner."""
        width, height = self.placement.rect[2:]
        return width, height

    def _import_target(self, graph: FrameGraph, rendering: Any, extent: tuple[int, int]) -> None:
        target = self.output.target
        last = self.placement.last
        graph.import_image(
            "target",
            handle=rendering.image,
            view=rendering.view,
            format=target.color_format,
            extent=self.placement.size,
            layout_before="UNDEFINED" if self.first else ATTACHMENT,
            layout_after=_final_layout(self.output.vk, target.final_layout) if last else ATTACHMENT,
            stage_before=("COLOR_ATTACHMENT_OUTPUT", "ALL_TRANSFER"),  # acquire's wait, last readback
        )
