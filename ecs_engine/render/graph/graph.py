"""The frame graph: passes added in order, resources imported from outside, outputs; compiled
into an order, a culled set, transient resources (aliased) and barriers; executed into a
command buffer. Without a device (`FrameGraph(None)`) it plans only (tests, `describe`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, overload

from ...errors import UsageError
from ...gpu.owned import Owned
from ...gpu.pipeline import AttachmentFormats
from .access import RAY_TRACING_ONLY
from .barriers import EMPTY, Barrier, BarrierPlan, dependency_info, plan_barriers
from .builder import UNREPLAYABLE, Declarations, Pass, declare
from .compile import Structure, plan_structure
from .context import PassContext
from .describe import describe
from .formats import attachment_formats
from .graph_imports import GraphImports
from .imports import Imports
from .resources import GraphBuffer, GraphImage
from .transient import Packing, Transients, aspect_of, estimated_requirements, pack

if TYPE_CHECKING:
    from ...gpu.secondary import SecondaryBuffers


@dataclass
class _Recording:
    """What execute records with for one compile and one state of the imports."""

    state: object  # the Imports.state it was made for (held: its id stays unique)
    images: dict[str, GraphImage]
    buffers: dict[str, GraphBuffer]
    ctx: PassContext
    infos: dict[str, tuple[Any, Any]] = field(default_factory=dict)  # batch -> (pointer, info)


@dataclass
class Compiled:
    """One compile's result: the structure (order, culled, lifetimes), where the transients
    live, and the barrier plan; with a device, the transients themselves."""

    signature: tuple
    structure: Structure
    packing: Packing
    barriers: BarrierPlan
    transients: Transients | None
    formats: dict[str, str] = field(default_factory=dict)  # resource -> its format's name


class FrameGraph(GraphImports):
    UNREPLAYABLE = UNREPLAYABLE  # what Pass.key() returns to make every frame record again
    # call every pass's setup at each compile and fail where a pass's `declares()` stayed equal
    # while its declarations changed (tests/conftest.py turns it on)
    verify_declares = False

    def __init__(self, device: Any) -> None:
        self.device = device
        self._passes: list[Pass] = []
        self._outputs: list[str] = []
        self._owned = Owned(device) if device is not None else None
        self.compiled: Compiled | None = None
        # per Imports.state since the compile (a frame slot's comes round again): _recording's
        self._recordings: dict[int, _Recording] = {}
        self._renderings: dict[tuple, Any] = {}  # PassContext.begin_rendering's, per compile
        self.compiles = 0  # how many compiles did work (a cached one does none)
        # what a compile depends on, kept so that the per-frame check costs little: a count
        # moved by every change of passes, outputs, imports' shapes or declarations; the
        # passes' last declarations; the imports (graph/imports.py)
        self._version = 0
        self._declarations = Declarations()
        self._table = Imports(device.vk if device is not None else None, self._vk)
        self._by_name: dict[str, Pass] | None = None
        self._running: tuple | None = None

    # ------------------------------------------------------------------ declaring the frame
    def add_pass(self, p: Pass, *, before: str | None = None) -> None:
        """Add `p` after the passes added so far, or just before the pass named `before` (a
        plugin placing itself ahead of, say, the tone map)."""
        if not isinstance(p, Pass) or not p.name:
            raise UsageError(f"{p!r} is not a Pass with a name")
        if any(q.name == p.name for q in self._passes):
            raise UsageError(f"the frame graph already has a pass named {p.name!r}")
        at = len(self._passes)
        if before is not None:
            names = [q.name for q in self._passes]
            if before not in names:
                raise UsageError(f"no pass {before!r} to add {p.name!r} before; passes: {', '.join(names)}")
            at = names.index(before)
        self._passes.insert(at, p)
        self._changed()

    def remove_pass(self, name: str) -> Pass:
        """Take a pass out (not destroyed: the caller now owns it)."""
        for i, p in enumerate(self._passes):
            if p.name == name:
                self._changed()
                return self._passes.pop(i)
        raise UsageError(f"the frame graph has no pass named {name!r}")

    @property
    def passes(self) -> tuple[Pass, ...]:
        return tuple(self._passes)

    def has_pass(self, name: str) -> bool:
        return name in self._passes_by_name()

    def _vk(self) -> Any:
        if self.device is not None:
            return self.device.vk
        from ...gpu.loader import load_vulkan

        return load_vulkan()

    @property
    def version(self) -> int:
        """Moves with every change a compile plans again for: passes, outputs, an import's shape,
        a pass's declarations."""
        return self._version

    def compiled_for(self, extent: tuple[int, int]) -> bool:
        """Whether the last compile stands for `extent` and everything since (a compile would
        do nothing)."""
        return self.stands(self._version, extent)

    def stands(self, version: int, extent: tuple[int, int]) -> bool:
        """Whether the graph is still at `version` and compiled for it and `extent` (one call
        for frame replay's check, which runs every frame)."""
        compiled = self.compiled
        return version == self._version and compiled is not None and compiled.signature == (extent, version)

    def _changed(self) -> None:
        """Passes, outputs or an import's shape changed: the next compile plans again."""
        self._version += 1
        self._by_name = self._running = None

    def output(self, name: str) -> None:
        """A resource the frame must produce: the passes writing it (and what they need) run."""
        if name not in self._outputs:
            self._outputs.append(name)
            self._changed()

    # ------------------------------------------------------------------ compiling
    def compile(self, extent: tuple[int, int]) -> None:
        """Order, cull, lifetimes, aliasing and barriers; nothing is done again while the
        passes' declarations, the imports (other than their handles), the outputs and the
        extent are the same."""
        extent = (int(extent[0]), int(extent[1]))
        if min(extent) < 1:
            raise UsageError(f"the frame graph's extent must be positive, not {extent}")
        declared, changed = self._declarations.of(self._passes, self.verify_declares)
        if changed:
            self._changed()
        signature = (extent, self._version)
        if self.compiled is not None and self.compiled.signature == signature:
            return
        structure = plan_structure(declared, self._table.by_name, tuple(self._outputs), extent)
        transients = None
        if self.device is not None:
            assert self._owned is not None
            if len(self._owned):
                self.device.wait_idle()  # frames in flight may still use the old transients
            self._owned.destroy()
            self.compiled = None
            try:
                transients = Transients(self.device, structure, self._owned)
            except BaseException:
                self._owned.destroy()
                raise
            packing = transients.packing
        else:
            packing = pack(estimated_requirements(structure))
        formats = {name: res.format for name, res in structure.resources.items()}
        barriers = plan_barriers(structure, packing)
        self.compiled = Compiled(signature, structure, packing, barriers, transients, formats)
        self._recordings.clear()
        self._renderings.clear()
        self.compiles += 1

    def _ready(self) -> Compiled:
        if self.compiled is None:
            raise UsageError("the frame graph is not compiled: call compile(extent) first")
        return self.compiled

    @property
    def order(self) -> list[str]:
        return list(self._ready().structure.order)

    @property
    def culled(self) -> list[str]:
        return list(self._ready().structure.culled)

    @property
    def transient_bytes(self) -> int:
        return self._ready().packing.transient_bytes

    @property
    def unaliased_bytes(self) -> int:
        return self._ready().packing.unaliased_bytes

    # ------------------------------------------------------------------ recording
    def _recording(self, c: Compiled) -> _Recording:
        """What execute records with, for this compile and the imports as they stand."""
        state = self._table.state
        kept = self._recordings.get(id(state))
        if kept is not None and kept.state is state:
            return kept
        t = c.transients
        images, buffers = (dict(t.images), dict(t.buffers)) if t else ({}, {})
        images.update(self._table.images)
        buffers.update(self._table.buffers)
        s, made = c.structure, self._renderings
        ctx = PassContext(self.device, s.extent, images, buffers, c.formats, s.dont_store, made)
        if len(self._recordings) >= 16:  # imports come and go (swapchain remakes, grown buffers)
            self._recordings.clear()
        kept = self._recordings[id(state)] = _Recording(state, images, buffers, ctx)
        return kept

    def execute(self, cb: Any, on_pass_end: Callable[[str], None] | None = None) -> None:
        """Record the passes that run, each after its batch of barriers, then the imports'
        transitions to their layout_after. `on_pass_end(name)` is called after each pass is
        recorded (outside any rendering: a timestamp may be written there)."""
        c = self._ready()
        if self.device is None:
            raise UsageError("a frame graph without a device only plans; it cannot execute")
        lib = self.device.vk.lib
        rec = self._recording(c)
        ctx = rec.ctx
        ctx._rendering = False  # a pass that raised last frame may have left it begun
        uses, before = c.structure.uses, c.barriers.before
        by_name = self._passes_by_name()
        for name in c.structure.order:
            rows = before[name]
            if rows:
                lib.vkCmdPipelineBarrier2(cb, self._info(c, rec, name, rows))
            ctx._enter(cb, name, uses[name])
            by_name[name].record(cb, ctx)
            ctx._leave()
            if on_pass_end is not None:
                on_pass_end(name)
        if c.barriers.after:
            lib.vkCmdPipelineBarrier2(cb, self._info(c, rec, "", c.barriers.after))

    def _info(self, c: Compiled, rec: _Recording, batch: str, rows: list[Barrier]) -> Any:
        """The VkDependencyInfo of a batch of barriers, made once per recording state."""
        cached = rec.infos.get(batch)
        if cached is not None:
            return cached[0]
        vk = self.device.vk
        aspects = {n: aspect_of(vk, res.format) for n, res in c.structure.resources.items() if res.kind == "image"}
        drop = EMPTY if self.device.features.get("rayTracing") else RAY_TRACING_ONLY
        images = {n: i.handle for n, i in rec.images.items()}
        info = dependency_info(vk, rows, images, {n: b.handle for n, b in rec.buffers.items()}, aspects, drop)
        pointer = vk.ffi.addressof(info)  # for the raw call (the binding's wrapper costs more)
        rec.infos[batch] = (pointer, info)
        return pointer

    def attachment_formats(self, colors: tuple[str, ...] = (), depth: str | None = None) -> AttachmentFormats:
        """The VkFormats and sample count of these attachments, from the passes' declarations
        and the imports (compiled or not): what a pipeline or a secondary drawn into them needs."""
        if self.compiled is not None:
            descs = {n: r.desc for n, r in self.compiled.structure.resources.items() if r.desc is not None}
        else:
            descs = {name: desc for p in self._passes for name, desc in declare(p).creates}
        return attachment_formats(self._vk(), colors, depth, descs, self._table.by_name)

    def inheritance(self, secondaries: SecondaryBuffers, colors: tuple[str, ...] = (), depth: str | None = None) -> Any:
        """The begin info of secondaries drawn inside a pass's `begin_rendering(colors, depth,
        secondaries=True)`: the attachments' formats inherited (SecondaryBuffers.begin_info_rendering,
        one per formats, kept by it). Needs no compile, so jobs may begin their secondaries
        before the primary is opened."""
        return secondaries.begin_info_rendering(self.attachment_formats(colors, depth))

    @overload
    def key(self) -> tuple: ...
    @overload
    def key(self, replayable: bool, handles: tuple | None = None) -> tuple | None: ...
    def key(self, replayable: bool = False, handles: tuple | None = None) -> tuple | None:
        """What a recorded frame depends on: each running pass's (name, key()) in order, the extent, the
        imported handles (`handles`: a snapshot's the caller knows are today's; equal keys: a kept
        command buffer draws the same); None (`replayable`) if UNREPLAYABLE."""
        run = self._run()
        keys = [k() for k in run[2]]
        if UNREPLAYABLE in keys:
            if replayable:
                return None
            keys = [object() if k is UNREPLAYABLE else k for k in keys]  # equal to no other key
        c = run[0]
        return (*zip(run[1], keys), c.structure.extent, self._table.handles() if handles is None else handles)

    def pass_keys(self) -> list | None:
        """The running passes' key()s in order, or None if one is UNREPLAYABLE: `key()` less what
        a caller that keeps this graph's compile and imports by identity already holds (frame
        replay's kept entry: passes/output_graph.py)."""
        run = self._running
        if run is None or run[0] is not self.compiled:  # (_run's check, inline: asked every replayed frame)
            run = self._run()
        keys = [k() for k in run[2]]
        return None if UNREPLAYABLE in keys else keys

    def _run(self) -> tuple:
        """(the compile, its running passes' names in order, their key methods), kept per compile."""
        run = self._running
        c = self.compiled
        if run is None or run[0] is not c:
            by_name, c = self._passes_by_name(), self._ready()
            order = c.structure.order
            run = self._running = (c, tuple(order), [by_name[name].key for name in order])
        return run

    def _passes_by_name(self) -> dict[str, Pass]:
        if self._by_name is None:
            self._by_name = {p.name: p for p in self._passes}
        return self._by_name

    def replayable(self) -> bool:
        """Whether a recorded frame can be replayed at all: no pass that runs returns UNREPLAYABLE."""
        return self.key(replayable=True) is not None

    def describe(self) -> str:
        """The passes in order, what each reads and writes and the barriers before it, then
        the transients with their sizes and places in memory."""
        c = self._ready()
        return describe(c.structure, c.packing, c.barriers)

    def destroy(self) -> None:
        """The transients and the passes (last added first); a second call does nothing."""
        if self._owned is not None:
            if len(self._owned):
                self.device.wait_idle()
            self._owned.destroy()
        self.compiled = None
        passes, self._passes = self._passes, []
        for p in reversed(passes):
            p.destroy()
