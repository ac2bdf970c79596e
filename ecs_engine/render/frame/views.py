"""Several camera views (components/camera_views.py): cameras drawing into a RenderTexture
(texture_views.py: its own target, copied into the texture's layer) first, then the window's
(split screen, a picture-in-picture), each into its rectangle of the same target image
(view_graph.py). Each view is drawn as a frame of its own through the renderer's one-frame
machinery (draw_frame.py). A window drawn whole by one camera keeps the window's own output
graph and form (a world with a monitor but no split screen); a split window is drawn in the hdr
form at least (target_forms.py). A texture view whose texture no material samples is skipped.

- A world whose cameras have no Viewport or RenderTexture draws as before: `several_views` is
  the one check the window's one camera pays (kept per world structure).
- Each view's frame takes the next frame slot (its buffers and descriptor set are the slot's;
  its primary, secondaries and replay record the view's own in that slot: view_frames.py); the
  swapchain's acquire semaphore is waited by the first view's submit, the present semaphore
  signalled by the last one's; the readback and the overlay go with the last view. The queue
  runs the submits in order; each graph's barriers chain with the one before's (view_graph.py).
- Per view: its camera's matrices and layers, a FrameExtractor per camera entity (temporal
  culling's history, the planes and chunk splits kept per camera), the shadow views planned
  from its camera (cascades follow it), its light clusters, its output graph (view_graph.py: one
  per place in the order, so each keeps its own compiled graph and transients at its size),
  and what keeps descriptor sets for one graph's images: its deferred lighting (DeferredPass)
  and copies of the window's hdr-stage post effects; so a still split screen waits for nothing
  and writes no set once made. Shared: the world's snapshot of materials, textures, meshes,
  the environment and the shadow map images (drawn again in each view's frame, before its
  scene reads them).
- Frame replay is per view and slot, and a frame's key names its view's graph, rectangle and
  camera: a still view replays in every slot it has recorded in, however many views take turns
  over the slots (view_frames.py; a view gone takes its command buffers with it).
- Post effects run in each view's graph at the view's size: bloom and SSAO over its "hdr",
  FXAA into its rectangle (view_graph.py); a texture view's into its whole target.
  Refused with several views (UsageError, one message): occlusion culling (the GPU keeps one
  depth pyramid of the last frame, which would be another view's) and effects given as
  callables (they get the whole HDR image).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ...errors import UsageError
from ..config import Form
from ..draw.path import FrameStats
from ..extract.frame_data import FrameData, FrameExtractor
from ..extract.views import ViewData, extract_views, several_views
from ..lighting.deferred import DeferredPass
from ..passes.output_graph import OutputGraph
from .draw_frame import FrameRequest
from .texture_views import TextureGraph, TextureTarget
from .view_frames import ViewRecordings
from .view_graph import Placement, ViewGraph


class Views:
    """The renderer's per-view state (see the module); `on` while the last world drew through it
    (the target's form follows: target_forms.py)."""

    def __init__(self, threads: Callable[[], int]) -> None:
        self.threads = threads
        self.on = False  # the views' path drew the last frame
        self.split = False  # ... with the window split (or a part of it drawn): the hdr form
        self.graphs: list[ViewGraph] = []  # the window's views', by place in the drawing order
        self.extractors: dict[int, FrameExtractor] = {}  # by camera entity
        self.targets: dict[str, TextureTarget] = {}  # the texture views', by texture name
        self.texture_graphs: dict[str, TextureGraph] = {}  # and their output graphs
        self.lighting: dict[Any, DeferredPass] = {}  # the deferred lighting per view (_lighting)
        self.effects: dict[Any, tuple[list[Any], list[Any]]] = {}  # per view: (the window's, copies)
        self.drawn: list[tuple[str, Any]] = []  # the last frame's views: (what, its output graph)
        self.recordings = ViewRecordings()  # each view's own per frame slot (frame replay: view_frames.py)

    def graph(self, r: Any, index: int) -> ViewGraph:
        """The output graph of the window's view at `index`, with the output's ldr effects (made
        again when those change, after the device is idle: frames in flight may use the old)."""
        output = r.output
        effects = output.graph.effects
        if any(g.effects != effects for g in self.graphs):
            r.device.wait_idle()
            for g in self.graphs:
                g.destroy()
            self.graphs.clear()
        while len(self.graphs) <= index:
            self.graphs.append(ViewGraph(output, not self.graphs, effects))
        return self.graphs[index]

    def extractor(self, camera: int, chunk_rows: int | None) -> FrameExtractor:
        found = self.extractors.get(camera)
        if found is None:
            found = self.extractors[camera] = FrameExtractor(self.threads, chunk_rows)
        return found

    def draw(self, r: Any, request: FrameRequest) -> FrameStats | None:
        """The frame of every view (renderer `r`: render's `request`), or None when the world
        draws its one camera over the whole window (Renderer.render's own path)."""
        world, readback, framebuffer = request.world, request.readback, request.framebuffer
        wait, signal, dt = request.wait, request.signal, request.dt
        width, height = request.extent or (r.target.width, r.target.height)
        views = extract_views(world, width, height) if several_views(world) else ()
        window = [v for v in views if v.texture is None]
        split = bool(views) and not (len(window) == 1 and window[0].rect == (0, 0, width, height))
        materials = r.materials(world) if views else None
        handles = [(v, self._handle(materials, v)) for v in views if v.texture is not None]
        textures = [(v, h) for v, h in handles if h is not None]
        self._drop_textures(r, {v.texture for v, _ in textures})
        if not textures and not split:
            if self.on:
                self.on = self.split = False
                self.forget(r)
            return None
        self._refuse(r)
        assert materials is not None
        r._blends = materials.blends
        self.on, self.split = True, split
        r.ensure_output()  # with several window views the hdr form at least (view_graph.py)
        drawn: list[tuple[ViewData, int | None]] = [*textures, *((v, None) for v in window)]
        datas = [self._extract(r, world, view, materials, dt) for view, _ in drawn]  # a bad world fails here
        output = r.output
        if output.graph is None:
            output.graph = OutputGraph(output, [])
        plain, overlay, target, lighting, post = output.graph, r.overlay, r.target, output.deferred, output.post
        stats = []
        self.drawn = []
        owners = [
            ("texture", view.texture) if handle is not None else ("window", i - len(textures))
            for i, (view, handle) in enumerate(drawn)
        ]
        recordings = self.recordings
        recordings.drop(r, set(owners))  # the views gone: their command buffers
        try:
            r.overlay = None
            for i, ((view, handle), data) in enumerate(zip(drawn, datas, strict=True)):
                first, last = i == 0, i == len(drawn) - 1
                recordings.owner = owners[i]
                # the acquire's wait goes with the first submit that touches the window's image:
                # the last view's where its UI draws the window (the editor's viewport: viewport.py)
                waits = last if getattr(target, "window_image", None) is not None else first
                semaphores = (wait if waits else None, signal if last else None)
                w, h = view.rect[2:]
                if handle is not None:  # into its own target, copied into the texture's layer
                    output.graph = self._texture_graph(r, view, handle)
                    output.deferred = self._lighting(r, view.texture, lighting)
                    output.post = self._effects(r, view.texture, post)
                    r.target = output.target = self._target(r, view, target)
                    stats.append(r._draw(data, materials, w, h, None, False, *semaphores))
                    recordings.give_back(r)
                    r.target = output.target = target
                    self.drawn.append(
                        (f"camera {view.view.entity} into texture {view.texture!r} {w}x{h}", output.graph)
                    )
                    continue
                output.graph = plain
                place = i - len(textures) if split else None
                output.deferred, output.post = self._lighting(r, place, lighting), self._effects(r, place, post)
                if split:
                    graph = output.graph = self.graph(r, i - len(textures))
                    graph.placement = Placement(view.rect, (width, height), last, view.view.entity)
                r.overlay = overlay if last else None
                stats.append(r._draw(data, materials, w, h, framebuffer, readback and last, *semaphores))
                recordings.give_back(r)
                self.drawn.append((f"camera {view.view.entity} into the window at {view.rect}", output.graph))
        finally:
            recordings.give_back(r)  # (a frame that failed)
            recordings.owner = None
            output.graph, r.overlay, r.target, output.target = plain, overlay, target, target
            output.deferred, output.post = lighting, post
        return _total(stats)

    def _lighting(self, r: Any, key: Any, window: Any) -> Any:
        """The deferred lighting of a view's graphs (`key`: its place among the window's views,
        or its texture's name; None: the window's own). Its set names one target's G-buffer
        and re-naming it waits for the device, so each view keeps its own (the deferred form
        only; made on first use)."""
        if key is None or r.target.form != Form.DEFERRED:
            return window
        found = self.lighting.get(key)
        if found is None:
            found = self.lighting[key] = DeferredPass(r.device, r.set_layout.handle)
        return found

    def _effects(self, r: Any, key: Any, window: list[Any]) -> list[Any]:
        """The hdr-stage post effects of a view's graphs (`key` as _lighting's): copies of the
        window's with the same settings, since an effect's pipelines keep descriptor sets for
        one graph's images (bloom forgets them, waiting for the device, when another graph's
        come); made again when the window's change."""
        if key is None or not window:
            return window
        made = self.effects.get(key)
        if made is not None and made[0] is window:
            return made[1]
        if made is not None:
            r.device.wait_idle()  # frames in flight may use them
            for effect in made[1]:
                if effect not in made[0]:  # a copy (an effect without settings is shared)
                    effect.destroy()
        copies = [type(p)(p.device, p.settings) if hasattr(p, "settings") else p for p in window]
        self.effects[key] = (window, copies)
        return copies

    def _handle(self, materials: Any, view: ViewData) -> int | None:
        """The texture a texture view draws: the render target of its name that a material
        samples (Textures.render_target), or None when none does (nothing would show it)."""
        assert view.view.texture is not None
        name, width, height = view.view.texture
        textures = materials.textures
        handle = textures.render_target_handle(name)
        if handle is None:
            return None
        made = textures.render_target_of(handle)
        if (made.width, made.height) != (width, height):
            raise UsageError(
                f"the camera drawing render texture {name!r} draws {width} x {height} pixels, and the "
                f"texture the materials sample was made {made.width} x {made.height}: make them one size"
            )
        return int(handle)

    def _target(self, r: Any, view: ViewData, window: Any) -> TextureTarget:
        """The texture view's own target, made again when its size or the window's format,
        samples change (after the device is idle: frames in flight may draw the old one)."""
        name = view.texture
        assert name is not None
        w, h = view.rect[2:]
        found = self.targets.get(name)
        if found is not None and not found.fits(w, h, window):
            r.device.wait_idle()
            self.targets.pop(name).destroy()
            found = None
        if found is None:
            found = self.targets[name] = TextureTarget(r.device, w, h, window)
        if found.form != window.form:  # the window's formats: its pipelines draw into it
            found.set_form(window.form)
        return found

    def _texture_graph(self, r: Any, view: ViewData, handle: int) -> TextureGraph:
        """The texture view's output graph, with the window's ldr effects (made again when
        they or the texture change, after the device is idle: frames in flight may use it)."""
        name = view.texture
        assert name is not None
        # the window's: the output's graph is the window's now, or the texture view's drawn
        # just before this one (texture views come first), made with the same effects
        effects = r.output.graph.effects
        found = self.texture_graphs.get(name)
        if found is None or found.handle != handle or found.effects != effects:
            if found is not None:
                r.device.wait_idle()
                found.destroy()
            found = self.texture_graphs[name] = TextureGraph(r.output, r.texture_pages, handle, name, effects)
        return found

    def _refuse(self, r: Any) -> None:
        refusal = r.culling_method.views_refusal
        if refusal is not None:
            raise UsageError(refusal)
        if any(not hasattr(p, "add_hdr") for p in r.output.post):
            raise UsageError(
                "a post effect given as a callable with several camera views: it gets the whole HDR "
                "image, not one view's (bloom, ssao and fxaa are drawn per view)"
            )

    def _extract(self, r: Any, world: Any, view: ViewData, materials: Any, dt: float | None) -> FrameData:
        """The view's snapshot by its camera's own extractor (its culling's state its own)."""
        extractor = self.extractor(view.view.entity, r.chunk_rows)
        w, h = view.rect[2:]
        culling = r.culling_method.name  # a method per extractor: temporal culling keeps its rows per camera
        args = (culling, len(materials), materials.set_aside(), None, dt, r.meshes.bounds())
        return extractor.extract(
            world, w / h, len(r.meshes), *args, materials=materials, camera=view.camera, layers=view.layers
        )

    def describe(self) -> str:
        """The last frame's views, in order, each with its output graph (--print-graph)."""
        parts = [
            f"view {i + 1} of {len(self.drawn)}: {what}\n{graph.describe()}"
            for i, (what, graph) in enumerate(self.drawn)
        ]
        return "\n".join(parts)

    def _drop_textures(self, r: Any, drawn: set[Any]) -> None:
        """What texture views no longer drawn kept (their target, graphs, lighting, effects'
        copies), once the device is idle: frames in flight may draw them."""
        gone = [name for name in self.targets if name not in drawn]
        if not gone:
            return
        r.device.wait_idle()
        for name in gone:
            self.targets.pop(name).destroy()
            for made in (self.texture_graphs.pop(name, None), self.lighting.pop(name, None)):
                if made is not None:
                    made.destroy()
            window, copies = self.effects.pop(name, ([], []))
            for effect in copies:
                if effect not in window:
                    effect.destroy()

    def forget(self, r: Any) -> None:
        """Back to the window's one camera: the extractors go (a camera's history would be
        stale), and the window views' graphs, lighting and effects' copies (their transients'
        memory) once the device is idle."""
        self.extractors.clear()
        self.recordings.drop(r, set())  # (the slots' rows are the window camera's from now)
        if not (self.graphs or self.lighting or self.effects):
            return
        r.device.wait_idle()
        for graph in self.graphs:
            graph.destroy()
        self.graphs.clear()
        for key in [k for k in self.lighting if k not in self.targets]:
            self.lighting.pop(key).destroy()
        for key in [k for k in self.effects if k not in self.targets]:
            window, copies = self.effects.pop(key)
            for effect in copies:
                if effect not in window:
                    effect.destroy()

    def destroy(self) -> None:
        self.recordings.destroy()
        for graph in [*self.graphs, *self.texture_graphs.values()]:
            graph.destroy()
        for target in self.targets.values():
            target.destroy()
        for lighting in self.lighting.values():
            lighting.destroy()
        self.lighting.clear()
        for window, copies in self.effects.values():
            for effect in copies:
                if effect not in window:
                    effect.destroy()
        self.effects.clear()
        self.graphs.clear()
        self.texture_graphs.clear()
        self.targets.clear()
        self.extractors.clear()


def _total(stats: list[FrameStats]) -> FrameStats:
    """The views' frames counted as one."""
    gpu = [s.gpu_ms for s in stats if s.gpu_ms is not None]
    return FrameStats(
        draws=sum(s.draws for s in stats),
        instances=sum(s.instances for s in stats),
        triangles=sum(s.triangles for s in stats),
        lights=stats[-1].lights,
        gpu_ms=sum(gpu) if gpu else None,
        wait_ms=sum(s.wait_ms for s in stats),
        record_ms=sum(s.record_ms for s in stats),
        chunks=sum(s.chunks for s in stats),
        candidates=sum(s.candidates for s in stats),
        replayed=all(s.replayed for s in stats),
    )
