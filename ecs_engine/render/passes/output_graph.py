"""The frame's output after the shadow maps, culling and (deferred) lighting as one frame graph
per target form (render/frame/output_passes.py; graph_plan.md step 7, first part):

    forward    the scene's rendering (render/passes/forward.py): into "target" (direct) or "hdr"
    post       the hdr stage's post effects (hdr and deferred forms)
    tone_map   "hdr" -> "target", or -> "ldr_0" (a transient of the target's format) with post
               effects of the "ldr" stage on (post/registry.py: FXAA)
    <effect i> "ldr_i" -> "ldr_i+1", the last one -> "target"
    imgui      the overlay over "target" (loaded: drawn on top); records nothing without one

"hdr", "hdr_msaa" and "depth" are still the target's SceneAttachments (imported each frame: the
deferred form's G-buffer pass and lighting write them before the graph runs), but for the direct
form's depth, the graph's transient. "target" is the
target's image for this frame, imported with its old contents discarded (UNDEFINED) after the
acquire semaphore's wait (colour output) and the last frame's readback copy of the same image
(transfer), and left as a colour attachment, which output_barriers.py's `after` takes to its
final layout (readback or present): the graph's own transition to PRESENT_SRC ends in no stage,
which the swapchain's readback barrier (from colour output) cannot follow. The graph places every
barrier between them, and the intermediates are its transients. Each ldr effect adds its own
passes (`effect.add(graph, source, target, create)`), so the graphs are made again when the
effects change; one graph is kept per (form, samples, target format).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

from ..graph import Access, FrameGraph, ImageDesc, Load, Pass
from ..graph.resources import format_name
from .forward import Forward, PostSeam

#: the graph's pass names -> the names the frame's timing marks have always used
_MARKS = {"tone_map": "tone map", "post": "post effects"}


class _Frame:
    """What this frame's passes draw with (set before each execute)."""

    state: Any = None
    tone_map: tuple[str, float] = ("clamp", 0.0)
    overlay: Any = None
    slot: int = 0
    secondaries: tuple[Any, ...] | list[Any] = ()  # the scene rendering's, in order (output_passes.py)
    reads: tuple[Any, ...] | list[Any] = ()  # (name, Access) forward reads of the scene's passes
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)  # fixed per renderer


class ToneMapInto(Pass):
    """The output's tone map (tone_map.py's pass, owned by the output passes) into `image`
    (made by the graph when `desc` is given, else an import: the target)."""

    name = "tone_map"

    def __init__(self, output: Any, frame: _Frame, image: str, desc: ImageDesc | None) -> None:
        self.output, self.frame, self.image, self.desc = output, frame, image, desc

    def setup(self, builder: Any) -> None:
        if self.desc is not None:
            builder.create(self.image, self.desc)
        builder.read("hdr", Access.FRAGMENT_SAMPLED)
        builder.write(self.image, Access.COLOR_WRITE)  # every pixel: not loaded

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


class OutputGraph:
    """The output graphs (see the module) of one list of ldr effects (maybe none)."""

    def __init__(self, output: Any, effects: list[Any]) -> None:
        self.output, self.effects = output, list(effects)
        self.frame = _Frame()
        self.frame.background = output.clear_color
        self.graphs: dict[tuple[str, int, int], FrameGraph] = {}
        self.graph: FrameGraph | None = None  # the last frame's

    def _make(self, form: str, samples: int, color_format: int) -> FrameGraph:
        device = self.output.device
        graph = FrameGraph(device)
        try:
            scene = self.output.scene  # the renderer's passes ahead of forward (frame/scene_passes.py)
            if scene is not None and scene.joins(form):
                scene.add_to(graph)
            graph.add_pass(Forward(self.frame, form, samples))
            if form != "direct":
                graph.add_pass(PostSeam(self.output, samples))
                desc = ImageDesc(format=f"VK_FORMAT_{format_name(device.vk, color_format)}")
                names = [f"ldr_{i}" for i in range(len(self.effects))] + ["target"]
                graph.add_pass(ToneMapInto(self.output, self.frame, names[0], desc if self.effects else None))
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
        secondaries: list[Any],
        tone_map: tuple[str, float],
        overlay: Any,
        slot: int,
        mark: Callable[[str], None] | None,
    ) -> None:
        """This frame's output: `rendering` (output_passes.OutputRendering) names the target's
        image and holds its barrier to the final layout; `secondaries` are the scene's draws."""
        target = self.output.target
        attachments = target.attachments
        form, samples, color_format = target.form, int(attachments.samples), int(target.color_format)
        shape = (form, samples, color_format)
        graph = self.graphs.get(shape)
        if graph is None:
            graph = self.graphs[shape] = self._make(*shape)
        self.graph = graph
        extent = (int(state.area.extent.width), int(state.area.extent.height))
        self._import_attachments(graph, form, attachments)
        self._import_target(graph, rendering, extent)
        frame = self.frame
        frame.state, frame.tone_map, frame.overlay, frame.slot = state, tone_map, overlay, slot
        frame.secondaries = secondaries
        scene = self.output.scene if self.output.scene is not None and self.output.scene.joins(form) else None
        if scene is not None:
            scene.import_into(graph)
        frame.reads = scene.reads if scene is not None else ()
        graph.compile(extent)
        names = {"forward": "sky and blended"} if form == "deferred" else {}

        def ended(name: str) -> None:
            if mark is None or (name == "imgui" and overlay is None) or (name == "post" and not self.output.post):
                return
            mark(names.get(name, _MARKS.get(name, scene.marks.get(name, name) if scene is not None else name)))

        graph.execute(cb, on_pass_end=ended if mark is not None else None)
        rendering.barriers.after(self.output.vk.lib, cb)
        frame.state = frame.overlay = None
        frame.secondaries = ()

    def _import_attachments(self, graph: FrameGraph, form: str, attachments: Any) -> None:
        """The target's SceneAttachments: depth, the HDR colour and, with MSAA, the multisampled
        one (images: depth, colour, resolve); none in the direct form (its depth is a transient).
        Nothing after the graph reads them: no final layout (UNDEFINED). The deferred form's
        come from the lighting (see forward.py)."""
        if form == "direct":
            return
        images = attachments.images
        deferred = form == "deferred"
        named = [("depth", images[0], "DEPTH_STENCIL_READ_ONLY_OPTIMAL" if deferred else "UNDEFINED")]
        named.append(("hdr", images[-1], "GENERAL" if deferred else "UNDEFINED"))
        if form == "hdr" and attachments.samples > 1:
            named.append(("hdr_msaa", images[1], "UNDEFINED"))
        for name, image, before in named:
            graph.import_image(
                name,
                handle=image.handle,
                view=image.view,
                format=image.format,
                extent=(int(image.width), int(image.height)),
                samples=int(attachments.samples) if name != "hdr" else 1,
                layout_before=before,
                layout_after="UNDEFINED",
            )

    def _import_target(self, graph: FrameGraph, rendering: Any, extent: tuple[int, int]) -> None:
        """The target's image, imported with its format's value (FXAA's pipeline is made for it)."""
        graph.import_image(
            "target",
            handle=rendering.image,
            view=rendering.view,
            format=self.output.target.color_format,
            extent=extent,
            layout_before="UNDEFINED",  # every pixel is written: the old contents go
            layout_after="COLOR_ATTACHMENT_OPTIMAL",  # then OutputBarriers.after (see the module)
            stage_before=("COLOR_ATTACHMENT_OUTPUT", "ALL_TRANSFER"),  # acquire's wait, last readback
        )

    def describe(self) -> str:
        return self.graph.describe() if self.graph is not None and self.graph.compiled is not None else ""

    def destroy(self) -> None:
        """The graphs and the passes they hold (the effects' passes too; not the effects)."""
        for graph in self.graphs.values():
            graph.destroy()
        self.graphs.clear()
        self.graph = None
