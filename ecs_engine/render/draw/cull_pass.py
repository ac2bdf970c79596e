"""The indirect path's compute as frame graph passes, one per step (graph_plan.md step 9; issue
36: the graph places the barriers from what each declares, none by hand between them):

    cull.zero           the counters zeroed (and occlusion's new visibility)
    cull.early          occlusion's early cull: last frame's visible rows      (occlusion only)
    cull.early_compact  their draw commands                                    (occlusion only)
    occlusion.depth     their depth, drawn                                     (occlusion only)
    occlusion.pyramid   the depth pyramid                                      (occlusion only)
    cull.rezero         the counters zeroed again for the late cull            (occlusion only)
    cull.frustum        every row against the frustum                          (no occlusion)
    cull.late           every row against the frustum and the pyramid          (occlusion only)
    cull.compact        the frame's draw commands
    cull.readback       the counters copied for the host
    cull.host           nothing recorded: its HOST_READ makes the graph place the copy's barrier
                        to the host's read after the frame's fence

The frame slot's buffers ("draws.ids", "draws.commands", "draws.state", "draws.readback") are
imported per frame; occlusion's depth image, pyramid and visibility, shared by the frames in
flight, are imported from OcclusionPasses (culling/occlusion_passes.py: the depth's contents do
not outlive the frame; the visibility carries the last frame's verdict to the early cull). The
scene's rendering declares its reads of the draws (`reads`). A path without GPU compute (the
CPU ones) declares nothing: the graph culls every pass. The steps' recording is
indirect_compute.py's."""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

from ..culling.occlusion_passes import DEPTH, PYRAMID, VISIBILITY
from ..graph import Access, Load, Pass

IDS, COMMANDS, STATE, READBACK = "draws.ids", "draws.commands", "draws.state", "draws.readback"
RW, W = Access.COMPUTE_READ_WRITE, Access.COMPUTE_WRITE

ALWAYS, OCCLUSION, FRUSTUM = "always", "occlusion", "frustum"  # when a step runs


def _zero(b: Any, g: CullPasses) -> None:
    b.write(STATE, Access.TRANSFER_WRITE)
    if g.fresh:  # a new visibility buffer, zeroed before its first early cull
        b.write(VISIBILITY, Access.TRANSFER_WRITE)


def _early(b: Any, g: CullPasses) -> None:
    b.read(VISIBILITY, Access.COMPUTE_READ)  # the last frame's late cull wrote it
    b.write(STATE, RW)
    b.write(IDS, W)


def _compact(b: Any, g: CullPasses) -> None:
    b.write(STATE, RW)  # the lists' lengths
    b.write(COMMANDS, W)


def _depth(b: Any, g: CullPasses) -> None:
    b.read(COMMANDS, Access.INDIRECT_READ)
    b.read(STATE, Access.INDIRECT_READ)
    b.read(IDS, Access.VERTEX_STORAGE_READ)
    b.write(DEPTH, Access.DEPTH_WRITE, load=Load.CLEAR)  # 0: reverse-Z's far


def _pyramid(b: Any, g: CullPasses) -> None:
    b.read(DEPTH, Access.DEPTH_SAMPLED)  # the layout occlusion's descriptor names
    b.write(PYRAMID, RW)  # each level reads the one below


def _rezero(b: Any, g: CullPasses) -> None:
    b.write(STATE, Access.TRANSFER_WRITE)  # after the early draws read the counts


def _frustum(b: Any, g: CullPasses) -> None:
    b.write(STATE, RW)
    b.write(IDS, W)


def _late(b: Any, g: CullPasses) -> None:
    b.read(PYRAMID, Access.COMPUTE_READ)
    b.write(VISIBILITY, W)  # the next frame's early rows
    b.write(STATE, RW)
    b.write(IDS, W)  # after the early draws read them


def _readback(b: Any, g: CullPasses) -> None:
    b.read(STATE, Access.TRANSFER_READ)
    b.write(READBACK, Access.TRANSFER_WRITE)
    b.side_effect()


def _host(b: Any, g: CullPasses) -> None:
    b.read(READBACK, Access.HOST_READ)
    b.side_effect()  # the host reads the counts


def _record_readback(cb: Any, ctx: Any, g: CullPasses) -> None:
    g.path.compute.readback(cb)
    g.path.pending = None  # recorded: the next frame's finish makes it ready again


# name, when it runs, its declarations, its recording
STEPS: tuple[tuple[str, str, Callable[[Any, Any], None], Callable[[Any, Any, Any], None] | None], ...] = (
    ("cull.zero", ALWAYS, _zero, lambda cb, ctx, g: g.path.compute.zero(cb)),
    ("cull.early", OCCLUSION, _early, lambda cb, ctx, g: g.path.compute.cull(cb, False)),
    ("cull.early_compact", OCCLUSION, _compact, lambda cb, ctx, g: g.path.compute.compact(cb)),
    ("occlusion.depth", OCCLUSION, _depth, lambda cb, ctx, g: g.path.compute.depth(cb, ctx, DEPTH)),
    ("occlusion.pyramid", OCCLUSION, _pyramid, lambda cb, ctx, g: g.path.compute.pyramid(cb)),
    ("cull.rezero", OCCLUSION, _rezero, lambda cb, ctx, g: g.path.compute.zero(cb)),
    ("cull.frustum", FRUSTUM, _frustum, lambda cb, ctx, g: g.path.compute.cull(cb, False)),
    ("cull.late", OCCLUSION, _late, lambda cb, ctx, g: g.path.compute.cull(cb, True)),
    ("cull.compact", ALWAYS, _compact, lambda cb, ctx, g: g.path.compute.compact(cb)),
    ("cull.readback", ALWAYS, _readback, _record_readback),
    ("cull.host", ALWAYS, _host, None),
)

#: the passes' names -> the frame's timing mark (frame/scene_passes.py): the one they had as one
#: pass, so that timings stay comparable (the perf log and monitor add up a name's spans)
MARKS = dict.fromkeys((name for name, *_ in STEPS), "culling (compute)")


class CullStep(Pass):
    def __init__(self, group: CullPasses, name: str, when: str, setup: Callable, record: Callable | None) -> None:
        self.name = name
        self.group = group
        self.when = when
        self._setup = setup
        self._record = record

    def runs(self) -> bool:
        g = self.group
        if g.path is None:
            return False
        occlusion = g.occlusion is not None
        return self.when == ALWAYS or (self.when == OCCLUSION) == occlusion

    def setup(self, builder: Any) -> None:
        if self.runs():
            self._setup(builder, self.group)

    def declares(self) -> Hashable:
        return self.group.state

    def record(self, cb: Any, ctx: Any) -> None:
        if self._record is not None:
            self._record(cb, ctx, self.group)


class CullPasses:
    """The steps' passes and what they share this frame: the path (None: no GPU compute), its
    occlusion passes (None: the frustum alone) and the slot's buffers."""

    def __init__(self) -> None:
        self.path: Any = None  # this frame's IndirectPath with its compute made ready, or None
        self.occlusion: Any = None
        self.fresh = False
        self.buffers: dict[str, Any] = {}
        self.state: tuple = (False, False, False)  # what the passes declare from
        self.passes = [CullStep(self, *step) for step in STEPS]

    def begin(self, path: Any, slot: int) -> None:
        ready = getattr(path, "pending", None) is not None
        self.path = path if ready else None
        self.buffers = path.draw_buffers(slot) if ready else {}
        compute = getattr(path, "compute", None) if ready else None
        self.occlusion = getattr(compute, "occlusion", None)
        self.fresh = bool(self.occlusion is not None and self.occlusion.fresh)
        self.state = (ready, self.occlusion is not None, self.fresh)

    def reads(self) -> list[tuple[str, Access]]:
        """What the draws of the scene's rendering read of them this frame."""
        if self.path is None:
            return []
        return [
            (COMMANDS, Access.INDIRECT_READ),
            (STATE, Access.INDIRECT_READ),  # the draw counts
            (IDS, Access.VERTEX_STORAGE_READ),
        ]

    def imports(self) -> Hashable:
        """What import_into imports besides the slot's buffers (equal: the same imports)."""
        return self.occlusion.imports() if self.occlusion is not None else None

    def import_into(self, graph: Any) -> None:
        if self.occlusion is not None:
            self.occlusion.import_into(graph)
