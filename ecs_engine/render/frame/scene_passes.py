"""The scene's passes that run ahead of the output's `forward` in the output's frame graph
(render/passes/output_graph.py; graph_plan.md step 9): the indirect path's compute ("cull"),
the light clusters, then the shadow maps. The renderer owns them (their pipelines live in the
renderer's parts: the path, LightCulling, ShadowPass); `begin` hands them the frame's inputs
and names the frame slot's buffers the graph imports (the maps are imported too), and `reads`
is what `forward` reads of what they write (so the graph places the barriers between them).

The deferred form's G-buffer, ray shadows and lighting are still recorded by hand before the
output graph runs (frame/output_passes.py), and they read what these passes write: in that form
the passes run as a graph of their own ahead of them (`record_alone`), whose buffers are made
visible to every later command at its end. That goes once those are the output graph's passes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..draw.cull_pass import CullPass
from ..graph import Access, FrameGraph, Pass
from ..lighting.clusters import ClusterGrid, LightClustersPass
from ..shadows.maps_graph import ShadowCullPass, ShadowMapsPass
from ..shadows.views import ShadowView

#: the passes' names -> the names the frame's timing marks have always used
MARKS = {
    "cull": "culling (compute)",
    "light_clusters": "light clusters",
    "shadow_cull": "shadow culling (compute)",  # was timed within "shadow maps"
    "shadow_maps": "shadow maps",
}


class ScenePasses:
    def __init__(self, device: Any, lights: Any, shadows: Any) -> None:
        self.device = device
        self.cull = CullPass()
        self.clusters = LightClustersPass(lights.pass_)
        self.shadows = ShadowMapsPass(shadows)
        self.passes: list[Pass] = [self.cull, self.clusters, ShadowCullPass(self.shadows), self.shadows]
        self.buffers: dict[str, Any] = {}  # name -> the frame slot's Buffer, imported this frame
        self.reads: list[tuple[str, Access]] = []  # what `forward` reads of them this frame
        self._alone: FrameGraph | None = None
        self.marks = MARKS

    def begin(
        self,
        path: Any,
        slot: int,
        frame: Any,
        grid: ClusterGrid | None,
        light_count: int,
        views: list[ShadowView],
        shadow_buffers: list[list[Any]],
    ) -> None:
        """This frame's inputs; `path`: the render path (its compute made ready by finish);
        `frame`: the slot's FrameResources; `shadow_buffers`: per view the secondaries the jobs
        recorded."""
        self.cull.begin(path, slot)
        self.clusters.begin(grid, frame.set_array, light_count)
        self.shadows.begin(views, shadow_buffers)
        self.buffers = {"clusters": frame.clusters, **self.cull.buffers}
        self.reads = self.cull.reads()
        self.reads += [("clusters", Access.FRAGMENT_READ)] if grid is not None else []
        self.reads += self.shadows.reads()

    @staticmethod
    def joins(form: str) -> bool:
        """Whether the passes run in the output graph of a target in `form` (see the module)."""
        return form != "deferred"

    def add_to(self, graph: FrameGraph) -> None:
        for p in self.passes:
            graph.add_pass(p)

    def import_into(self, graph: FrameGraph, visible_after: bool = False) -> None:
        for name, buffer in self.buffers.items():  # the frame slot's: its last use was fenced
            graph.import_buffer(
                name, handle=buffer.handle, size=buffer.size, visible_after=visible_after, stage_before="NONE"
            )
        self.shadows.import_into(graph)

    def record_alone(self, cb: Any, extent: tuple[int, int], mark: Callable[[str], None] | None) -> None:
        """The passes as a graph of their own (the deferred form: see the module)."""
        if self._alone is None:
            self._alone = FrameGraph(self.device)
            self.add_to(self._alone)
        self.import_into(self._alone, visible_after=True)
        self._alone.compile(extent)
        self._alone.execute(cb, on_pass_end=None if mark is None else lambda name: mark(MARKS.get(name, name)))

    def destroy(self) -> None:
        """The alone graph (the passes destroy nothing: their pipelines are their owners')."""
        if self._alone is not None:
            self._alone.destroy()
            self._alone = None
