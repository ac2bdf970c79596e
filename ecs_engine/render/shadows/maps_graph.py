"""The shadow maps as the frame graph's "shadow_maps" pass (graph_plan.md step 9): ShadowPass
(maps_pass.py) draws this frame's views into their layers of the map array, which the graph
imports as "shadow_maps" (every layer in the layout the lighting samples before and after the
frame). The pass declares a write of each drawn layer's corner (`region`: the rest of the layer
is kept), or the first time of every layer whole (cleared, so none is ever read undefined);
the passes that sample the maps declare DEPTH_SAMPLED reads, so the graph places the barriers
that ShadowMaps.barriers made by hand. A frame without views (after the first) declares nothing
and the graph culls the pass. The views' secondaries are recorded by the chunk jobs with the
maps' formats' inheritance (ShadowPass.secondary_begin), as the rendering expects."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ...gpu.shadow_maps import READ_LAYOUT_NAME, SHADOW_FORMAT_NAME
from ..graph import Access, FrameGraph, Load, Pass
from .views import ShadowView

NAME = "shadow_maps"


class ShadowMapsPass(Pass):
    name = NAME

    def __init__(self, shadows: Any) -> None:
        self.shadows = shadows  # the renderer's ShadowPass
        self.views: list[ShadowView] = []  # this frame's (begin)
        self.secondaries: list[list[Any]] = []
        self.culled: dict[str, Any] = {}  # the buffers ShadowCullPass writes this frame

    def begin_views(self, views: list[ShadowView]) -> None:
        """This frame's views (what the pass declares: known before the jobs record them; the
        GPU-culled views' buffers as the last `begin` left them until `begin` names this frame's)."""
        self.views = views
        gpu = self.shadows.gpu if views else None
        self.culled = gpu.draw_buffers() if gpu is not None else {}  # shadow_cull's, this frame

    def begin(self, views: list[ShadowView], secondaries: list[list[Any]]) -> None:
        self.secondaries = self.shadows.gpu_culled(secondaries) if views else secondaries
        self.begin_views(views)  # the GPU-culled views' buffers: those gpu_culled prepared

    @staticmethod
    def reads() -> list[tuple[str, Access]]:
        """What the scene's rendering reads of the maps: every frame, as the frame's descriptor
        set names them (the 1-texel maps too) in the layout the lighting samples."""
        return [(NAME, Access.DEPTH_SAMPLED)]

    def setup(self, builder: Any) -> None:
        for name in self.culled:  # the GPU-culled views' commands, counts and ids
            if name.endswith(".commands") or name.endswith(".state"):
                builder.read(name, Access.INDIRECT_READ)
            elif name.endswith(".ids"):
                builder.read(name, Access.VERTEX_STORAGE_READ)
        if not self.views:
            return
        for view in self.views:  # (every layer was cleared when the maps were made: ShadowMaps)
            builder.write(NAME, Access.DEPTH_WRITE, layer=view.layer, load=Load.CLEAR, region=True)
        builder.side_effect()  # the lighting may sample them outside the graph (frame/scene_passes.py)

    def declares(self) -> Hashable:
        return (tuple(self.culled), tuple(view.layer for view in self.views) if self.views else ())

    def record(self, cb: Any, ctx: Any) -> None:
        self.shadows.record(cb, ctx, self.views, self.secondaries)

    def key(self) -> Hashable:
        # the views' secondaries are recorded anew each frame (frame/replay.py's rule)
        return FrameGraph.UNREPLAYABLE if self.views else None

    def import_into(self, graph: FrameGraph) -> None:
        graph.import_slot_buffers(self.culled)
        maps = self.shadows.maps
        token = (id(maps), maps.image.handle, maps.resolution, maps.layers)  # all the import is made from
        if graph.reuse_import(NAME, token):
            return
        graph.import_image(
            NAME,
            handle=maps.image.handle,
            view=maps.image.view,
            format=SHADOW_FORMAT_NAME,
            extent=(maps.resolution, maps.resolution),
            layers=maps.layers,
            layer_views=tuple(maps.layer_views),
            layout_before=READ_LAYOUT_NAME,  # or never written: the first frame clears every layer
            layout_after=READ_LAYOUT_NAME,
            # the last frame's readers and depth tests (frames in flight share the maps): what
            # ShadowMaps.barriers waited for by hand
            stage_before=("FRAGMENT_SHADER", "COMPUTE_SHADER", "EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"),
            token=token,
        )


class ShadowCullPass(Pass):
    """The indirect mode's GPU culling of the shadow views (indirect.py: cull, compact, the
    counters' copy for the host) ahead of "shadow_maps", which declares its reads of the
    views' buffers: the graph places the barrier to their draws (compute_barriers' `to_draw`
    before). Nothing to cull: nothing declared, culled."""

    name = "shadow_cull"

    def __init__(self, maps: ShadowMapsPass) -> None:
        self.maps = maps

    def setup(self, builder: Any) -> None:
        culled = self.maps.culled
        if not culled:
            return
        for name in culled:
            if name.endswith(".state"):
                builder.write(name, Access.TRANSFER_WRITE)  # zeroed
                builder.read(name, Access.TRANSFER_READ)  # copied for the host
            builder.write(name, Access.TRANSFER_WRITE if name.endswith("readback") else Access.COMPUTE_READ_WRITE)
        builder.side_effect()

    def declares(self) -> Hashable:
        return tuple(self.maps.culled)

    def record(self, cb: Any, ctx: Any) -> None:
        self.maps.shadows.gpu.record_compute(cb)
