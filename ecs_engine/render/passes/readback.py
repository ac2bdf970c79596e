"""The target's readback as the output graph's last pass (render/passes/output_graph.py): the
finished "target" read by a transfer (TRANSFER_SRC_OPTIMAL, the graph's barrier from the colour
writes) and copied to the target's host buffer (gpu/offscreen.py, gpu/swapchain.py
`record_copy`, which also makes the copy visible to the host). The graph then takes "target" to
its final layout: a headless target's is TRANSFER_SRC itself (nothing more), a swapchain image's
PRESENT_SRC (from the copy). A headless target keeps the pass every frame (its image ends in
TRANSFER_SRC anyway) and copies only when asked; a swapchain's graph has it only on the frames
that read back (a screenshot), since the transfer layout is a barrier more and needs the
surface's TRANSFER_SRC usage."""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

from ..graph import Access, Pass

#: a target's copy: (command buffer, the target's VkImage in TRANSFER_SRC_OPTIMAL, its extent)
Copy = Callable[[Any, Any, tuple[int, int]], None]


class Readback(Pass):
    """Reads `source` ("target", or "window" where the UI draws the target into the window:
    output_frame.py) by transfer; copies it when `frame.readback` (a Copy) is set."""

    name = "readback"

    def __init__(self, frame: Any, source: str = "target") -> None:
        self.frame, self.source = frame, source

    def setup(self, builder: Any) -> None:
        builder.read(self.source, Access.TRANSFER_READ)
        builder.side_effect()  # writes the host buffer, outside the graph

    def declares(self) -> Hashable:
        return ()  # its setup declares the same every frame

    def record(self, cb: Any, ctx: Any) -> None:
        copy: Copy | None = self.frame.readback
        if copy is not None:
            image = ctx.image(self.source)
            copy(cb, image.handle, image.extent)

    def key(self) -> Hashable:
        return self.frame.readback is not None
