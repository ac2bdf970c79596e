"""The scene's passes that run ahead of the output's `forward` in the output's frame graph
(render/passes/output_graph.py; graph_plan.md step 9): the indirect path's compute (its steps'
passes, "cull.*" and "occlusion.*": draw/cull_pass.py),
the light clusters, then the shadow maps. The renderer owns them (their pipelines live in the
renderer's parts: the path, LightCulling, ShadowPass); `begin` hands them the frame's inputs
and names the frame slot's buffers the graph imports (the maps are imported too), and `reads`
is what `forward` reads of what they write (so the graph places the barriers between them).

The deferred form's G-buffer and lighting read them too (render/passes/deferred_passes.py takes
`reads` from the frame as forward does).
"""

from __future__ import annotations

from typing import Any

from ..draw.cull_pass import MARKS as CULL_MARKS
from ..draw.cull_pass import CullPasses
from ..graph import Access, FrameGraph, Pass
from ..lighting.clusters import ClusterGrid, LightClustersPass
from ..shadows.maps_graph import ShadowCullPass, ShadowMapsPass
from ..shadows.views import ShadowView

#: the passes' names -> the names the frame's timing marks have always used
MARKS = {
    **CULL_MARKS,
    **dict.fromkeys(LightClustersPass.STEPS, "light clusters"),  # added up, as the one pass was
    "shadow_cull": "shadow culling (compute)",  # was timed within "shadow maps"
    "shadow_maps": "shadow maps",
}


class ScenePasses:
    def __init__(self, device: Any, lights: Any, shadows: Any) -> None:
        self.device = device
        self.cull = CullPasses()
        self.clusters = LightClustersPass(lights.pass_)
        self.shadows = ShadowMapsPass(shadows)
        self.passes: list[Pass] = [*self.cull.passes, *self.clusters.passes, ShadowCullPass(self.shadows), self.shadows]
        self.buffers: dict[str, Any] = {}  # name -> the frame slot's Buffer, imported this frame
        self.reads: tuple[tuple[str, Access], ...] = ()  # what `forward` reads of them this frame
        self.marks = MARKS
        # a frame with nothing for the scene's passes to do (see begin_slot): per frame slot the
        # arguments and what they set ([token, buffers, reads, signature or None]), while the
        # passes' own state is the idle one (`_at_rest`)
        self._idle: dict[int, list[Any] | None] = {}
        self._at_rest = False
        self._kept: list[Any] | None = None  # this frame's entry of _idle, or None
        self._signature: tuple | None = None  # signature()'s, until the state changes

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
        self._at_rest, self._kept, self._signature = False, None, None
        self.cull.begin(path, slot)
        self.clusters.begin(grid, frame.set_array, light_count)
        self.shadows.begin(views, shadow_buffers)
        self.buffers = {"clusters": frame.clusters, **self.cull.buffers}
        self.reads = self._reads(grid)

    def begin_slot(
        self, path: Any, slot: int, frame: Any, grid: ClusterGrid | None, light_count: int, views: list[ShadowView]
    ) -> None:
        """Before the frame's replay key (render/frame/replay.py) and its jobs: what the passes
        declare and the key's imports read (the slot's buffers, the clusters' inputs, the shadow
        views), so that the graph compiled for the key is the one recorded; `begin` then adds
        what the jobs made.

        A frame that culls on the CPU, draws no shadow map and clusters no lights (every frame
        that can be submitted again) sets what the slot's last such frame set, when its
        arguments and the maps are the same: that is brought back instead of made again (this
        runs every frame, before the replay key: frame/replay.py)."""
        token = None
        if not views and grid is None and getattr(path, "pending", None) is None:
            # the slot's set is written anew (set_version) for a grown clusters buffer and new maps
            token = (path, frame, frame.set_version, light_count, self.shadows.shadows.maps)
            kept = self._idle.get(slot)
            if self._at_rest and kept is not None and kept[0] == token:
                # the clusters' pass keeps what the last idle frame gave it (no grid: it records
                # nothing, keys None, and a recorded frame's `begin` names this slot's set)
                self.buffers, self.reads, self._signature, self._kept = kept[1], kept[2], kept[3], kept
                return
        self.cull.begin(path, slot)  # the indirect path's compute as its last frame left it
        self.clusters.begin(grid, frame.set_array, light_count)
        self.shadows.begin_views(views)
        self.buffers = {"clusters": frame.clusters, **self.cull.buffers}
        self.reads = self._reads(grid)
        self._signature = None
        self._at_rest = token is not None
        self._kept = self._idle[slot] = [token, self.buffers, self.reads, None] if token is not None else None

    def _reads(self, grid: ClusterGrid | None) -> tuple[tuple[str, Access], ...]:
        reads = self.cull.reads()
        reads += [("clusters", Access.FRAGMENT_READ)] if grid is not None else []
        return tuple(reads + self.shadows.reads())  # a tuple: the passes' declares() return it

    def add_to(self, graph: FrameGraph) -> None:
        for p in self.passes:
            graph.add_pass(p)

    def signature(self) -> tuple:
        """What import_into imports and the passes declare from, by identity: equal signatures,
        equal imports and declarations (the output graph's prepare keeps a frame slot's imports
        under it: passes/output_graph.py). Kept until begin or begin_slot changes the state."""
        if self._signature is None:
            self._signature = self._signed()
            if self._kept is not None:
                self._kept[3] = self._signature
        return self._signature

    def _signed(self) -> tuple:
        shadows = self.shadows
        maps = shadows.shadows.maps
        image = maps.image if maps is not None else None
        return (
            self.cull.path,
            self.cull.imports(),
            tuple([(n, b, b.handle) for n, b in self.buffers.items()]),
            tuple([(n, b, b.handle) for n, b in shadows.culled.items()]),
            maps,
            image.handle if image is not None else None,
            self.reads,
            tuple([view.layer for view in shadows.views]) if shadows.views else (),
        )

    def import_into(self, graph: FrameGraph) -> None:
        graph.import_slot_buffers(self.buffers)
        self.cull.import_into(graph)
        self.shadows.import_into(graph)

    def destroy(self) -> None:
        """Nothing: the passes' pipelines are their owners' (the path, LightCulling, ShadowPass)."""
