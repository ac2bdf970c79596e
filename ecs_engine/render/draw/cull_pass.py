"""The indirect path's compute passes as the frame graph's "cull" pass (graph_plan.md step 9,
first as one pass: zero the counters, cull, with occlusion culling its early draws, depth and
pyramid and the late cull, compact, copy the counters for the host; draw/indirect_path.py's
record_compute). It declares the frame slot's buffers it writes ("draws.ids", "draws.commands",
"draws.state", "draws.readback", imported per frame) and the scene's rendering declares its
reads of them (`reads`), so the graph places the barrier from the compute passes to the draws
that compute_barriers' `to_draw` made by hand at their end, and orders them after the slot's
last frame. The barriers inside (between the dispatches, the occlusion depth's) stay the pass's
own for now. A path without compute passes (the CPU ones) declares nothing: the graph culls it."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ..graph import Access, Pass


class CullPass(Pass):
    name = "cull"

    def __init__(self) -> None:
        self.path: Any = None  # this frame's IndirectPath with its compute made ready, or None
        self.buffers: dict[str, Any] = {}

    def begin(self, path: Any, slot: int) -> None:
        ready = getattr(path, "pending", None) is not None
        self.path = path if ready else None
        self.buffers = path.draw_buffers(slot) if ready else {}

    def reads(self) -> list[tuple[str, Access]]:
        """What the draws of the scene's rendering read of them this frame."""
        if self.path is None:
            return []
        return [
            ("draws.commands", Access.INDIRECT_READ),
            ("draws.state", Access.INDIRECT_READ),  # the draw counts
            ("draws.ids", Access.VERTEX_STORAGE_READ),
        ]

    def setup(self, builder: Any) -> None:
        if self.path is None:
            return
        builder.write("draws.state", Access.TRANSFER_WRITE)  # zeroed
        builder.write("draws.state", Access.COMPUTE_READ_WRITE)
        builder.read("draws.state", Access.TRANSFER_READ)  # copied for the host
        builder.write("draws.ids", Access.COMPUTE_READ_WRITE)
        builder.write("draws.commands", Access.COMPUTE_READ_WRITE)
        builder.write("draws.readback", Access.TRANSFER_WRITE)
        builder.side_effect()  # the host reads the counts; the G-buffer may draw outside the graph

    def declares(self) -> Hashable:
        return self.path is not None

    def record(self, cb: Any, ctx: Any) -> None:
        self.path.record_compute(cb)
