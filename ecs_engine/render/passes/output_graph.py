"""The frame's output after the shadow maps, culling and (deferred) lighting as one frame graph
per target form (render/frame/output_passes.py; graph_plan.md step 7, first part):

    forward    the scene's rendering (render/passes/forward.py): into "target" (direct) or "hdr"
    <post>     the hdr stage's post effects' passes (hdr and deferred forms; `add_hdr`,
               or a PostCall pass for a plain callable: render/passes/forward.py)
    tone_map   "hdr" -> "target", or -> "ldr_0" (a transient of the target's format) with post
               effects of the "ldr" stage on (post/registry.py: FXAA)
    <effect i> "ldr_i" -> "ldr_i+1", the last one -> "target"
    imgui      the overlay over "target" (loaded: drawn on top); records nothing without one;
               with a window image (the editor's viewport: frame/viewport.py) "target" is
               sampled and the UI draws "window" (output_frame.py), the graph's output
    readback   "target" (or "window") copied to the host (render/passes/readback.py): every
               frame of a headless target (copying when asked), a swapchain's reading-back frames

In the deferred form the scene's rendering follows the G-buffer, ray shadow, lighting and
weighted transparency passes (render/passes/deferred_passes.py).

The single-sample "hdr" and "depth" are still the target's SceneAttachments (imported each
frame; the tone map, PostInputs and the tone map's descriptor sets name them); the direct form's
depth, the MSAA colour and depth, the G-buffer, weighted transparency's targets, the effects'
images and "ldr_i" are the graph's transients (aliased where their lifetimes allow). "target" is
the target's image for this frame, imported with its old contents discarded (UNDEFINED) after
the acquire semaphore's wait (colour output) and the last frame's readback copy of the same
image (transfer), and left in the target's final layout (`final_layout`: TRANSFER_SRC
headless, PRESENT_SRC for a swapchain, SHADER_READ_ONLY for the viewport). The graph places
every barrier. Each ldr effect adds its own passes (`effect.add(graph, source, target,
create)`), so the graphs are made again when the effects change; one graph is kept per (form,
samples, target format, rays, weighted transparency, hdr effects and extent, window or not).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..config import Form
from ..graph import FrameGraph, ImageDesc
from ..graph.resources import format_name
from .deferred_passes import (
    DeferredLightingPass,
    GBufferPass,
    GBufferViews,
    OitAccumulatePass,
    RayDenoisePass,
    RayShadowsPass,
)
from .forward import Forward, PostCall
from .output_frame import OutputFrame, OverlayOver, ToneMapInto
from .output_imports import OutputImports, _final_layout  # noqa: F401 (view_graph.py imports it here)
from .readback import Readback

#: the graph's pass names -> the names the frame's timing marks have always used
_MARKS = {
    "tone_map": "tone map",
    "gbuffer": "g-buffer",
    "ray_denoise": "ray-traced shadows",
    "deferred_lighting": "lighting (compute)",
    "oit_accumulate": "transparency (accumulate)",
}


class OutputGraph(OutputImports):
    """The output graphs (see the module) of one list of ldr effects (maybe none)."""

    def __init__(self, output: Any, effects: list[Any]) -> None:
        self.output, self.effects = output, list(effects)
        self.frame = OutputFrame()
        self.frame.background = output.clear_color
        self.graphs: dict[tuple[Any, ...], FrameGraph] = {}
        self._post_names: frozenset[str] = frozenset()  # the hdr effects' passes (marked once, at the last)
        self.graph: FrameGraph | None = None  # the last frame's
        self._views: tuple[Any, Any, GBufferViews] | None = None  # _gbuffer_views' last
        self._recreations = getattr(output.target, "recreations", 0)  # the swapchain's, the graphs made in
        self._prepared: tuple[Any, Any, FrameGraph] | None = None  # prepare's, until record takes it
        # per frame slot: what its last full prepare read (_inputs), the shape, the graph and its
        # imports then (the slots alternate: each comes round with its own buffers; gone with the graph)
        self._kept: dict[int, tuple[tuple, tuple, FrameGraph, tuple]] = {}
        self._copies = False  # this frame's readback copies the target
        self._extent = (0, 0)  # this prepare's (the attachments' imports)

    def _make(self, form: Form, samples: int, color_format: int, ray: bool, oit: bool, post: Any) -> FrameGraph:
        device = self.output.device
        graph = FrameGraph(device)
        try:
            scene = self.output.scene  # the renderer's passes ahead of the scene (frame/scene_passes.py)
            if scene is not None:
                scene.add_to(graph)
            if form == Form.DEFERRED:
                frame = self.frame
                graph.add_pass(GBufferPass(frame))
                if ray:
                    graph.add_pass(RayShadowsPass(frame, self.output.deferred))
                    graph.add_pass(RayDenoisePass(frame, self.output.deferred))
                graph.add_pass(DeferredLightingPass(frame, self.output.deferred))
                if oit:
                    graph.add_pass(OitAccumulatePass(frame))
            graph.add_pass(Forward(self.frame, form, samples, oit))
            if form != Form.DIRECT:
                self._add_post(graph, samples, post)
                desc = ImageDesc(format=f"VK_FORMAT_{format_name(device.vk, color_format)}")
                names = [f"ldr_{i}" for i in range(len(self.effects))] + ["target"]
                graph.add_pass(ToneMapInto(self.output, self.frame, names[0], desc if self.effects else None))
                for i, effect in enumerate(self.effects):
                    effect.add(graph, names[i], names[i + 1], None if names[i + 1] == "target" else desc)
            graph.add_pass(OverlayOver(self.frame))
            graph.output("window" if self.frame.window is not None else "target")
        except BaseException:
            graph.destroy()
            raise
        return graph

    def prepare(
        self, state: Any, rendering: Any, tone_map: tuple[str, float], overlay: Any, slot: int, readback: bool = False
    ) -> FrameGraph:
        """This frame's graph, chosen by the target's shape, its imports made and compiled
        (cached while nothing changed), the frame's settings set: what its passes' keys read
        (frame replay asks before the jobs, render/frame/replay.py; `record` then reuses it).
        `rendering` (output_passes.OutputRendering) names the target's image; `readback`:
        copy the target to the host. When nothing it reads changed since the slot's last
        prepare, that one's imports are brought back instead of made again."""
        if readback:  # (a frame reading back prepares in full)
            self.frame.window = self._window(overlay)
            return self._prepare(state, rendering, tone_map, overlay, slot, readback, None)
        inputs, kept = self._slot_kept(state, overlay, slot)
        if kept is not None and kept[2].restore_imports(kept[3]):
            graph = kept[2]
            self._copies = False
            if not FrameGraph.verify_declares:
                # what the passes declare from is in `inputs` too: the graph compiled for them stands
                self._set_frame(graph, state, rendering, tone_map, overlay, slot, readback, compile=False)
                return graph
            # the tests: a full prepare imports the same, and its compile plans nothing new
            again, version = dict(graph._table.by_name), graph.version
            full = self._prepare(state, rendering, tone_map, overlay, slot, readback, inputs)
            assert full is graph and graph._table.by_name == again, "the kept imports are not this frame's"
            assert graph.version == version, "the passes declared anew under the same inputs"
            self._kept[slot] = kept  # the same entry (frame replay's key holds it by identity)
            return graph
        return self._prepare(state, rendering, tone_map, overlay, slot, readback, inputs)

    def _inputs(self, state: Any, overlay: Any) -> tuple:
        """What a prepare's graph, imports and the passes' declarations follow from (the frame's
        other settings only go into the passes' keys): equal inputs, equal shape, imports and
        plan. The state stands for the target's image, form and swapchain (one is made per
        output image, form and size, and anew with the swapchain: frame/output_passes.py)."""
        output = self.output
        target, scene = output.target, output.scene
        return (
            state,
            target.attachments,
            target.color_format,
            target.final_layout,
            output.ray_shadows,
            output.oit,
            self.frame.transparent is not None,
            tuple(output.post),
            scene.signature() if scene is not None else None,
            overlay is not None,
            self.frame.window,
        )

    def _window(self, overlay: Any) -> Any:
        """The window the UI draws the target into (the editor's viewport), or None: over the target."""
        return getattr(self.output.target, "window_image", None) if overlay is not None else None

    def _slot_kept(self, state: Any, overlay: Any, slot: int) -> tuple[tuple, Any]:
        """The frame's window and `_inputs`, and the slot's kept entry if made from them (or None)."""
        self.frame.window = None if overlay is None else self._window(overlay)  # (run every frame: no call without)
        inputs = self._inputs(state, overlay)
        kept = self._kept.get(slot)
        return inputs, kept if kept is not None and kept[0] == inputs else None

    def _set_frame(
        self,
        graph: FrameGraph,
        state: Any,
        rendering: Any,
        tone_map: Any,
        overlay: Any,
        slot: int,
        readback: bool,
        compile: bool = True,
    ) -> None:
        """This frame's settings into the graph's passes (their keys and declarations read them),
        the graph compiled (cached; `compile=False`: it stands as it was), kept for `record`."""
        self._settings(graph, state, tone_map, overlay, slot)
        output, frame = self.output, self.frame
        extent = (state.key[1], state.key[2])  # (the area's size, as Python ints)
        if compile or not graph.compiled_for(extent):
            graph.compile(extent)
        if output.target.form == Form.DEFERRED:
            frame.attachments = self._gbuffer_views(graph, output.target.attachments)
        self._prepared = ((state, rendering, overlay), (tone_map, slot, readback), graph)

    def _settings(self, graph: FrameGraph, state: Any, tone_map: Any, overlay: Any, slot: int) -> None:
        """What the passes' keys read: the effects' frame inputs, the state, tone map, overlay, slot."""
        output = self.output
        if output.post and output.inputs is not None:
            for effect in output.post:
                if hasattr(effect, "begin_frame"):
                    effect.begin_frame(output.inputs)
        self.graph = graph
        frame = self.frame
        frame.state, frame.tone_map, frame.overlay, frame.slot = state, tone_map, overlay, slot

    def key_again(self, state: Any, tone_map: Any, overlay: Any, slot: int) -> Any:
        """Frame replay's graph key without a prepare when the slot's kept entry has today's inputs
        and the graph stands for them (that version, compiled for the extent): `steady_key`'s
        (None: UNREPLAYABLE); else False (`record` prepares later)."""
        # _slot_kept's lines, inline: this runs every replayed frame, and a slot without an
        # entry returns before its inputs are built
        kept = self._kept.get(slot)
        if kept is None:
            return False
        self.frame.window = None if overlay is None else self._window(overlay)
        graph = kept[2]
        if kept[0] != self._inputs(state, overlay) or not graph.stands(kept[3][0], state.key[1:]):
            return False
        self._settings(graph, state, tone_map, overlay, slot)
        self._prepared = None
        keys = graph.pass_keys()
        key = None if keys is None else (kept, keys)
        if FrameGraph.verify_declares:  # the tests: a prepare's key is this one
            full = self.prepare(state, self.output._rendering(state), tone_map, overlay, slot)
            assert full is graph and self.steady_key(slot) == key, "a kept key that a prepare does not give"
            self._prepared = None
        return key

    def steady_key(self, slot: int) -> Any:
        """After a prepare without readback, the slot's graph key: its kept entry (by identity:
        the inputs, the graph's shape, version and imports, so its compile, extent and imported
        handles) and the running passes' keys; None for UNREPLAYABLE."""
        kept = self._kept[slot]
        keys = kept[2].pass_keys()
        return None if keys is None else (kept, keys)

    def _prepare(
        self,
        state: Any,
        rendering: Any,
        tone_map: tuple[str, float],
        overlay: Any,
        slot: int,
        readback: bool,
        inputs: tuple | None,
    ) -> FrameGraph:
        target = self.output.target
        attachments = target.attachments
        form, samples, color_format = target.form, int(attachments.samples), int(target.color_format)
        deferred = form == Form.DEFERRED
        # the rays' and weighted transparency's passes from the first frame with them on (idle on a frame
        # without traced lights or blended rows): one graph, one set of transients, as those come and go
        ray = deferred and self.output.ray_shadows is not None
        oit = deferred and (self.output.oit is not None or self.frame.transparent is not None)
        extent = (state.key[1], state.key[2])  # (the area's size, as Python ints)
        post = self.output.post if form != Form.DIRECT else []
        post_shape = (extent, tuple(id(p) for p in post)) if post else None  # the effects' passes follow both
        window = self.frame.window
        shape = (form, samples, color_format, ray, oit, post_shape, window is not None)
        recreations = getattr(target, "recreations", 0)
        if recreations != self._recreations:
            # new attachments, whose views may reuse destroyed ones' handle values, which the
            # effects' passes keep descriptor sets by: new graphs, new passes and sets
            self._recreations = recreations
            self._drop(list(self.graphs))
        graph = self.graphs.get(shape)
        if graph is None:
            self._drop([k for k in self.graphs if k[5] != post_shape or k[:3] == shape[:3]])  # outdone: gone
            graph = self.graphs[shape] = self._make(*shape[:6])  # (the window: self.frame's)
        self._copies = readback and target.take_readback()  # a swapchain's: only for the image asked
        final = window.final_layout if window is not None else target.final_layout
        headless = final == self.output.vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
        self._place_readback(graph, self._copies or headless)
        self._extent = extent
        self._import_attachments(graph, form, attachments)
        self._import_target(graph, rendering, extent)
        if window is not None:
            self._import_window(graph, window)
        self._import_scene(graph)
        self._set_frame(graph, state, rendering, tone_map, overlay, slot, readback)
        if inputs is not None:  # this slot's imports, for its next frame with the same inputs
            self._kept[slot] = (inputs, shape, graph, graph.imports_snapshot())
        return graph

    def _drop(self, shapes: list[tuple]) -> None:
        """The graphs of `shapes` destroyed, and the slots' kept imports of them forgotten."""
        for shape in shapes:
            (gone := self.graphs.pop(shape)).destroy()
            self._kept = {slot: kept for slot, kept in self._kept.items() if kept[2] is not gone}

    def forget_prepared(self) -> None:
        """A frame that asked `prepare` is not recorded: the next `record` prepares anew."""
        self._prepared = None

    def _taken(self, state: Any, rendering: Any, tone_map: Any, overlay: Any, slot: int, readback: bool) -> Any:
        """The graph `prepare` made this frame for the same arguments, or None."""
        kept, self._prepared = self._prepared, None
        if kept is None or any(a is not b for a, b in zip(kept[0], (state, rendering, overlay))):
            return None
        return kept[2] if kept[1] == (tone_map, slot, readback) else None

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
        readback: bool = False,
    ) -> None:
        """This frame's output (prepared here unless `prepare` was asked the same this frame);
        `secondaries` are the scene's draws."""
        graph = self._taken(state, rendering, tone_map, overlay, slot, readback)
        taken = graph is not None
        if graph is None:  # prepared now, after the jobs: with their inputs
            graph = self.prepare(state, rendering, tone_map, overlay, slot, readback)
            self._prepared = None
        target = self.output.target
        form = target.form
        copies = self._copies
        posts = [p.name for p in graph.passes if p.name in self._post_names] if mark is not None else None
        last_post = posts[-1] if posts else None
        frame = self.frame
        frame.secondaries = secondaries
        frame.readback = target.record_copy if copies else None
        oit_now = frame.transparent is not None
        scene = self.output.scene
        if scene is not None and taken:  # its frame's inputs came after `prepare` (the jobs'): imported again
            self._import_scene(graph)
            graph.compile((state.key[1], state.key[2]))
            if form == Form.DEFERRED:
                frame.attachments = self._gbuffer_views(graph, target.attachments)
        names = {"forward": "sky and blended"} if form == Form.DEFERRED else {}

        def ended(name: str) -> None:
            if mark is None or (name == "imgui" and overlay is None):
                return
            if name in self._post_names:  # the effects' passes: marked once, after the last
                if name == last_post:
                    mark("post effects")
                return
            if (name == "readback" and not copies) or name == "ray_shadows":  # marked with its denoise
                return
            idle = (name == "ray_denoise" and frame.ray is None) or (name == "oit_accumulate" and not oit_now)
            if idle:  # the pass recorded nothing
                return
            mark(names.get(name, _MARKS.get(name, scene.marks.get(name, name) if scene is not None else name)))

        graph.execute(cb, on_pass_end=ended if mark is not None else None)
        frame.state = frame.overlay = frame.readback = frame.ray = frame.transparent = frame.frame_set = None
        frame.attachments = None
        frame.secondaries = frame.chunks = ()

    def _import_scene(self, graph: FrameGraph) -> None:
        """The scene passes' buffers and maps, and what the scene's passes read of them."""
        scene = self.output.scene
        if scene is not None:
            scene.import_into(graph)
        self.frame.reads = scene.reads if scene is not None else ()

    def _add_post(self, graph: FrameGraph, samples: int, post: Any) -> None:
        """The hdr stage's effects in order: their own passes (`add_hdr`) or a PostCall each."""
        if post is None:
            return
        extent = post[0]
        before = {p.name for p in graph.passes}
        for i, effect in enumerate(self.output.post):
            if hasattr(effect, "add_hdr"):
                effect.add_hdr(graph, extent)
            else:
                graph.add_pass(PostCall(self.output, i, effect, samples))
        self._post_names = self._post_names | {p.name for p in graph.passes if p.name not in before}

    def _place_readback(self, graph: FrameGraph, wanted: bool) -> None:
        """The readback pass last in `graph` or not (a change recompiles the graph: a swapchain's
        screenshot frame and the one after)."""
        has = graph.has_pass(Readback.name)
        if wanted and not has:
            graph.add_pass(Readback(self.frame, "window" if self.frame.window is not None else "target"))
        elif has and not wanted:
            graph.remove_pass(Readback.name).destroy()

    def _gbuffer_views(self, graph: FrameGraph, attachments: Any) -> GBufferViews:
        """The GBufferViews of this compile of `graph` over `attachments` (one per pair)."""
        compiled = graph.compiled
        assert compiled is not None and compiled.transients is not None
        kept = self._views
        if kept is None or kept[0] is not compiled or kept[1] is not attachments:
            kept = self._views = (compiled, attachments, GBufferViews(attachments, compiled.transients.images))
        return kept[2]

    def describe(self) -> str:
        return self.graph.describe() if self.graph is not None and self.graph.compiled is not None else ""

    def destroy(self) -> None:
        """The graphs and the passes they hold (the effects' passes too; not the effects)."""
        self._drop(list(self.graphs))
        self.graph = None
