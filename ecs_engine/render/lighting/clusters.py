"""Clustered lighting: for thousands of lights, each fragment (forward) or each pixel of the
deferred lighting pass loops over the lights of its cluster instead of every light.

A cluster is a screen tile (TILE_PX square) times a distance bin: one of LIGHT_BINS exponential
shells around the eye, from s = max(near, reach / 100) to the farthest reach of any bounded light
(the last bin runs on to infinity). The grid is decoupled, after M. Drobot's "Improved culling
for tiled and clustered rendering" (SIGGRAPH 2017): each frame, before the render pass,
light_bounds.comp gives every distance bin the lowest and highest index of a light whose bounding
sphere reaches into it (the lights are sorted by distance from the eye: light_rows.py), and
light_tiles.comp gives every screen tile a bit mask over the lights whose sphere touches its
frustum. A fragment takes its bin's index range and walks its tile's mask words over that range.
Lights without a bound (directional ones, radius 0) go to a global list every fragment loops
over. Nothing is capped per cluster: the masks hold every light.

Measured on the GPU host (H100, 1280x720, the lights demo with 4,096 lights): the first version,
one workgroup per 32 px x 32-slice cluster listing lights whose sphere touches the cluster's box,
let each fragment evaluate ~77 lights where ~20 reach it; its dispatch alone took 2.25 ms of the
10.8 ms frame. This one: 0.26 ms for both passes, 5.3 ms the frame lit in the fragment shader,
1.8 ms lit in compute (deferred_pass.py; docs/performance.md has the steps). The light's window
function is exactly 0 beyond its radius (and a spot light's beyond its cone), so leaving it out
of a cluster it cannot reach changes nothing but the order of the sum (checked: images equal
the loop within 1/255).

Below CLUSTER_MIN_LIGHTS the simple loop stays: the compute passes, the lookups and the G-buffer
cost more than looping over a handful of lights (`python -m ecs_engine.bench lights` measures
where they cross). The renderer switches with hysteresis (on at the threshold, off below half of
it); a switch rebuilds the mesh pipelines (FEATURE_CLUSTERED is a specialisation constant) and,
with `auto`, changes the target's form (deferred, or forward again).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from ...gpu.device import Device
from ...gpu.owned import Owned
from ...gpu.pipeline import compute_pipeline, pipeline_layout
from ..config import LightCulling as LightCullingMode
from ..config import choice
from ..graph import Access, Pass
from ..layouts import CLUSTER_GROUP, CLUSTER_HEADER, LIGHT_BINS, MAX_GLOBAL_LIGHTS, UINT_BYTES
from .rows import DirectionalLights, PositionalLights

log = logging.getLogger("ecs_engine")

TILE_PX: Final = 16
# measured on the GPU host (H100, 1280x720, the lights demo, bench/results/lights-h100-16c.json):
# 6 lights 1.33 ms looping, 1.75 clustered, 1.58 deferred; 16 lights 2.18, 2.13 and 1.58
CLUSTER_MIN_LIGHTS: Final = 16
LIGHT_MODES: Final = LightCullingMode.names()
_FORCED: Final = (LightCullingMode.CLUSTERED, LightCullingMode.DEFERRED)  # cluster whenever the lights allow


@dataclass(frozen=True)
class ClusterGrid:
    tiles_x: int
    tiles_y: int
    lights: int  # point and spot lights (the masks' bits)
    near: float  # the bin near plane s: the first bin takes every distance below s too
    scale: float  # LIGHT_BINS / ln(far / s)
    width: int
    height: int
    tile: int

    @property
    def tiles(self) -> int:
        return self.tiles_x * self.tiles_y

    @property
    def words(self) -> int:
        """Mask words per tile."""
        return max(1, -(-self.lights // 32))

    @property
    def bounds_start(self) -> int:
        return CLUSTER_HEADER + 2 * LIGHT_BINS

    @property
    def masks_start(self) -> int:
        return self.bounds_start + 4 * self.words * 32

    @property
    def buffer_bytes(self) -> int:
        return (self.masks_start + self.tiles * self.words) * UINT_BYTES

    def bin_of(self, distance: np.ndarray) -> np.ndarray:
        """The bin each distance from the eye falls in (as the shaders compute it)."""
        d = np.maximum(np.asarray(distance, np.float64), self.near)
        return np.minimum((np.log(d / self.near) * self.scale).astype(np.int64), LIGHT_BINS - 1)


def cluster_grid(width: int, height: int, near: float, reach: float, lights: int) -> ClusterGrid:
    """The grid for a viewport, a camera's near plane and `lights` point and spot lights; `reach`:
    the farthest distance from the eye a bounded light touches (bins end there; beyond, the last
    one). Bins start at s = max(near, reach / 100): exponential bins from a tiny near plane would
    spend most of themselves on the first metre."""
    near = max(near, reach / 100.0)
    far = max(reach, near * 2.0)
    return ClusterGrid(
        tiles_x=-(-width // TILE_PX),
        tiles_y=-(-height // TILE_PX),
        lights=lights,
        near=near,
        scale=LIGHT_BINS / math.log(far / near),
        width=width,
        height=height,
        tile=TILE_PX,
    )


def light_census(
    positional: list[PositionalLights], directional: list[DirectionalLights], eye: np.ndarray
) -> tuple[int, int, float]:
    """(bounded lights, lights every fragment needs, the farthest distance from `eye` a bounded
    light reaches)."""
    bounded = unbounded = 0
    reach = 0.0
    for part in positional:
        radius = np.asarray(part.radius, np.float64)
        has = radius > 0
        n = int(has.sum())
        bounded += n
        unbounded += len(radius) - n
        if n:
            d = np.linalg.norm(np.asarray(part.position, np.float64)[has] - eye, axis=1) + radius[has]
            reach = max(reach, float(d.max()))
    unbounded += sum(len(d) for d in directional)
    return bounded, unbounded, reach


def wants_clusters(mode: str, clustered_now: bool, bounded: int, unbounded: int) -> bool:
    """Whether this frame's lights are clustered: `clustered`, `deferred` and `loop` force it
    (clustered only while the unbounded ones fit the global list), `auto` switches at
    CLUSTER_MIN_LIGHTS bounded lights, off again below half of that."""
    if unbounded > MAX_GLOBAL_LIGHTS or bounded == 0 or mode == LightCullingMode.LOOP:
        return False
    if mode in _FORCED:
        return True
    return bounded >= (CLUSTER_MIN_LIGHTS // 2 if clustered_now else CLUSTER_MIN_LIGHTS)


def check_light_culling(mode: str) -> None:
    choice("light_culling", mode)  # UsageError naming the choices


class ClusterPass:
    """light_bounds.comp then light_tiles.comp over the cluster buffer, after its fills (the
    frame graph's three light cluster passes record them: LightClustersPass below)."""

    def __init__(self, device: Device, frame_set_layout: Any) -> None:
        self.device = device
        self.owned = Owned(device)  # the layout, then the pipelines (made on first record)
        layout = self.layout = pipeline_layout(device, [frame_set_layout])
        self.owned.add(layout, lambda: device.vk.vkDestroyPipelineLayout(device.handle, layout, None))
        self.pipelines: list[Any] = []

    def zero(self, cb: Any, clusters: Any) -> None:
        """The global list's count and the depth bins' bounds (lowest index, highest) reset."""
        vk = self.device.vk
        lib = vk.lib
        bins = CLUSTER_HEADER * UINT_BYTES
        handle = clusters.handle
        lib.vkCmdFillBuffer(cb, handle, 0, UINT_BYTES, 0)  # the global list's count
        lib.vkCmdFillBuffer(cb, handle, bins, LIGHT_BINS * UINT_BYTES, 0xFFFFFFFF)  # lowest index
        lib.vkCmdFillBuffer(cb, handle, bins + LIGHT_BINS * UINT_BYTES, LIGHT_BINS * UINT_BYTES, 0)  # highest

    def dispatch(self, cb: Any, set_array: Any, step: int, groups: tuple[int, int]) -> None:
        """light_bounds.comp (`step` 0, one invocation per light) or light_tiles.comp (1, one
        group per tile); the graph's passes place the barriers between them and the fills."""
        vk = self.device.vk
        lib = vk.lib
        if not self.pipelines:
            self.pipelines = [self._pipeline(name) for name in ("light_bounds.comp", "light_tiles.comp")]
        lib.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.layout, 0, 1, set_array, 0, vk.ffi.NULL)
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.pipelines[step])
        lib.vkCmdDispatch(cb, groups[0], groups[1], 1)

    def _pipeline(self, shader: str) -> Any:
        device = self.device
        pipeline = compute_pipeline(device, shader, self.layout)
        return self.owned.add(pipeline, lambda: device.vk.vkDestroyPipeline(device.handle, pipeline, None))

    def destroy(self) -> None:
        self.owned.destroy()
        self.pipelines = []


class LightCulling:
    """The renderer's choice between the all-lights loop and clusters, frame by frame, and the
    cluster passes. `plan` says whether the pipelines must change."""

    def __init__(self, device: Device, frame_set_layout: Any, mode: str = LightCullingMode.AUTO) -> None:
        self.mode = mode
        self.clustered = False  # the mesh pipelines loop over cluster lists
        self.pass_ = ClusterPass(device, frame_set_layout)
        self.supported = bool(device.features.get("fragmentSubgroupArithmetic"))
        self.max_bytes = int(device.limits.maxStorageBufferRange)  # the cluster buffer is one binding
        self._warned = False
        self._warned_msaa = False

    @property
    def mode(self) -> LightCullingMode:
        return self._mode

    @mode.setter
    def mode(self, mode: str) -> None:
        check_light_culling(mode)  # UsageError naming the choices
        self._mode = LightCullingMode(mode)

    @property
    def walked_by_fragments(self) -> bool:
        """Whether forward fragments walk the grid (FEATURE_CLUSTERED: the `_clustered` shaders,
        which need subgroup arithmetic); without it they loop over every light, while the
        deferred lighting, in compute, still walks the grid."""
        return self.clustered and self.supported

    def plan(self, data: Any, width: int, height: int, samples: int = 1) -> tuple[ClusterGrid | None, bool]:
        """(this frame's grid or None, whether `clustered` changed)."""
        clustered = False
        reach = 0.0
        # on a device without fragment subgroup arithmetic only the deferred lighting walks the
        # grid: no grid where the lights are lit forward (`clustered`, or MSAA)
        if not self.supported and (self._mode == LightCullingMode.CLUSTERED or samples > 1):
            if self._mode in _FORCED and not self._warned:
                self._warned = True
                log.warning("this device has no subgroup arithmetic in fragment shaders: lights are not clustered")
            return None, False
        if self._mode != LightCullingMode.LOOP and (
            self.clustered or self._mode in _FORCED or data.light_count >= CLUSTER_MIN_LIGHTS // 2
        ):
            bounded, unbounded, reach = light_census(data.lights, data.directional, data.camera.position)
            clustered = wants_clusters(self._mode, self.clustered, bounded, unbounded)
        grid = None
        if clustered:
            positional = sum(len(p) for p in data.lights)
            grid = cluster_grid(width, height, data.camera.near, reach, positional)
        if grid is not None and grid.buffer_bytes > self.max_bytes:
            if not self._warned:
                self._warned = True
                log.warning(
                    "%d lights at %dx%d need a %d MiB light grid, more than the device binds: lights are not clustered",
                    positional,
                    width,
                    height,
                    grid.buffer_bytes >> 20,
                )
            grid, clustered = None, False
        flipped = clustered != self.clustered
        self.clustered = clustered
        return grid, flipped

    def deferred(self, samples: int) -> bool:
        """Whether the opaque meshes are lit in compute (the target's deferred form): asked for,
        or `auto` with clustered lights; never with MSAA (the G-buffer has one sample: MSAA
        keeps forward lighting, with one warning when deferred was asked for)."""
        deferred = self._mode == LightCullingMode.DEFERRED
        wanted = deferred or (self._mode == LightCullingMode.AUTO and self.clustered)
        if wanted and samples > 1:
            if deferred and not self._warned_msaa:
                self._warned_msaa = True
                log.warning("deferred lighting draws one sample per pixel: with --msaa %d lights stay forward", samples)
            return False
        return wanted

    def destroy(self) -> None:
        self.pass_.destroy()


class LightClustersPass(Pass):
    """One of the frame graph's three light cluster passes over the frame slot's cluster buffer
    ("clusters", imported per frame): "light_clusters.zero" (the fills), "light_clusters.bounds"
    (light_bounds.comp) and "light_clusters.tiles" (light_tiles.comp). Each declares its access,
    so the graph places the barriers between them (transfer -> compute, compute -> compute) and
    around them (its readers, forward fragments and the deferred lighting, declare their reads).
    A frame without a grid declares nothing, and the graph culls them. `begin` is the first
    pass's: the others share its frame inputs."""

    STEPS = ("light_clusters.zero", "light_clusters.bounds", "light_clusters.tiles")

    def __init__(self, clusters: ClusterPass, step: int = 0, first: LightClustersPass | None = None) -> None:
        self.clusters = clusters
        self.step = step
        self.name = self.STEPS[step]
        self.first = first or self
        self.grid: ClusterGrid | None = None  # this frame's (begin)
        self.set_array: Any = None
        self.light_count = 0
        self.others = [] if first is not None else [LightClustersPass(clusters, k, self) for k in (1, 2)]

    @property
    def passes(self) -> list[LightClustersPass]:
        return [self, *self.others]

    def begin(self, grid: ClusterGrid | None, set_array: Any, light_count: int) -> None:
        self.grid, self.set_array, self.light_count = grid, set_array, light_count

    def setup(self, builder: Any) -> None:
        if self.first.grid is None:
            return
        builder.write("clusters", Access.TRANSFER_WRITE if self.step == 0 else Access.COMPUTE_READ_WRITE)
        if self.step == 2:
            builder.side_effect()  # its readers may be recorded outside the graph (frame/scene_passes.py)

    def declares(self) -> Hashable:
        return self.first.grid is not None

    def record(self, cb: Any, ctx: Any) -> None:
        first = self.first
        grid = first.grid
        assert grid is not None
        if self.step == 0:
            self.clusters.zero(cb, ctx.buffer("clusters"))
        elif self.step == 1:
            self.clusters.dispatch(cb, first.set_array, 0, (-(-first.light_count // CLUSTER_GROUP), 1))
        else:
            self.clusters.dispatch(cb, first.set_array, 1, (grid.tiles_x, grid.tiles_y))

    def key(self) -> Hashable:
        grid = self.first.grid
        return None if grid is None else (self.step, grid.tiles_x, grid.tiles_y, self.first.light_count)
