"""Clustered forward lighting: for thousands of lights, each fragment loops over the lights of its
cluster instead of every light.

The view is cut into clusters: TILE_PX x TILE_PX screen tiles times SLICES depth slices,
exponential in view depth from the near plane to the farthest reach of any bounded light (the
last slice runs on to infinity). Each frame, before the render pass, cluster.comp lists per
cluster the point and spot lights whose sphere (position, radius) touches the cluster's box, and
once for all fragments the lights without a bound (directional ones, radius 0). The light's
window function is exactly 0 beyond its radius, so leaving it out of a cluster it cannot reach
changes nothing but the order of the sum (checked: images equal the loop within 1/255).

Below CLUSTER_MIN_LIGHTS the simple loop stays: the compute pass and the lookups cost more than
looping over a handful of lights (`python -m ecs_engine.bench lights` measures where they cross).
The renderer switches with hysteresis (on at the threshold, off below half of it); a switch
rebuilds the mesh pipelines (FEATURE_CLUSTERED is a specialisation constant).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from ..gpu.device import Device
from ..gpu.pipeline import compute_pipeline, pipeline_layout
from .layouts import (
    CLUSTER_HEADER,
    CLUSTER_PEAK,
    CLUSTER_STRIDE,
    MAX_CLUSTER_LIGHTS,
    MAX_GLOBAL_LIGHTS,
    UINT_BYTES,
)
from .light_rows import DirectionalLights, PositionalLights

log = logging.getLogger("ecs_engine")

TILE_PX: Final = 32
SLICES: Final = 32
POOL_PER_CLUSTER: Final = 32  # the index pool's first size, in light indices per cluster
# measured on the GPU host (H100, 1280x720, the lights demo, bench/results/lights-h100-16c.json):
# 6 lights 1.46 ms looping, 1.81 clustered; 16 lights 2.30 and 2.15; 64 lights 6.52 and 3.53
CLUSTER_MIN_LIGHTS: Final = 16
LIGHT_MODES: Final = ("auto", "loop", "clustered")


@dataclass(frozen=True)
class ClusterGrid:
    tiles_x: int
    tiles_y: int
    slices: int
    near: float  # the slice near plane s: the first slice takes every depth below s too
    scale: float  # slices / ln(far / s)
    width: int
    height: int
    tile: int = TILE_PX
    pool: int = 0  # the index pool's capacity (light indices); 0: POOL_PER_CLUSTER per cluster

    @property
    def count(self) -> int:
        return self.tiles_x * self.tiles_y * self.slices

    @property
    def pool_start(self) -> int:
        return CLUSTER_HEADER + self.count * CLUSTER_STRIDE

    @property
    def pool_capacity(self) -> int:
        return self.pool or self.count * POOL_PER_CLUSTER

    @property
    def buffer_bytes(self) -> int:
        return (self.pool_start + self.pool_capacity) * UINT_BYTES

    def slice_of(self, depth: np.ndarray) -> np.ndarray:
        """The slice each view depth falls in (as the fragment shader computes it)."""
        d = np.maximum(np.asarray(depth, np.float64), self.near)
        return np.minimum((np.log(d / self.near) * self.scale).astype(np.int64), self.slices - 1)


def cluster_grid(width: int, height: int, near: float, reach: float, pool: int = 0) -> ClusterGrid:
    """The grid for a viewport and a camera's near plane; `reach`: the farthest view distance a
    bounded light touches (slices end there; beyond, the last one). Slices start at
    s = max(near, reach / 100): exponential slices from a tiny near plane would spend most of
    themselves on the first metre."""
    near = max(near, reach / 100.0)
    far = max(reach, near * 2.0)
    return ClusterGrid(
        tiles_x=-(-width // TILE_PX),
        tiles_y=-(-height // TILE_PX),
        slices=SLICES,
        near=near,
        scale=SLICES / math.log(far / near),
        width=width,
        height=height,
        pool=pool,
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
    """Whether this frame's lights are clustered: `clustered` and `loop` force it (clustered only
    while the unbounded ones fit the global list), `auto` switches at CLUSTER_MIN_LIGHTS bounded
    lights, off again below half of that."""
    if unbounded > MAX_GLOBAL_LIGHTS or bounded == 0 or mode == "loop":
        return False
    if mode == "clustered":
        return True
    return bounded >= (CLUSTER_MIN_LIGHTS // 2 if clustered_now else CLUSTER_MIN_LIGHTS)


def check_light_culling(mode: str) -> None:
    from ..errors import UsageError

    if mode not in LIGHT_MODES:
        raise UsageError(f"unknown light culling {mode!r}; choices: {', '.join(LIGHT_MODES)}")


class ClusterPass:
    """cluster.comp, recorded into the frame's primary command buffer before the render pass."""

    def __init__(self, device: Device, frame_set_layout: Any) -> None:
        self.device = device
        self.layout = pipeline_layout(device, [frame_set_layout])
        self.pipeline: Any = None

    def record(self, cb: Any, set_array: Any, grid: ClusterGrid, clusters: Any, peak: Any) -> None:
        """The dispatch, and the largest cluster's light count copied to `peak` (a host buffer the
        renderer reads once the frame is done)."""
        vk = self.device.vk
        lib = vk.lib
        if self.pipeline is None:
            self.pipeline = compute_pipeline(self.device, "cluster.comp", self.layout)
        at = CLUSTER_PEAK * UINT_BYTES  # the peak and the pool's use, zeroed, then read back
        vk.vkCmdFillBuffer(cb, clusters.handle, at, 2 * UINT_BYTES, 0)
        self._barrier(
            cb,
            clusters,
            vk.VK_ACCESS_TRANSFER_WRITE_BIT,
            vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT,
            vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
            vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
        )
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.pipeline)
        lib.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.layout, 0, 1, set_array, 0, vk.ffi.NULL)
        lib.vkCmdDispatch(cb, grid.count + 1, 1, 1)  # the last group lists the unbounded lights
        self._barrier(
            cb,
            clusters,
            vk.VK_ACCESS_SHADER_WRITE_BIT,
            vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_TRANSFER_READ_BIT,
            vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
            vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
        )
        region = vk.VkBufferCopy(srcOffset=at, dstOffset=0, size=2 * UINT_BYTES)
        vk.vkCmdCopyBuffer(cb, clusters.handle, peak.handle, 1, [region])

    def _barrier(self, cb: Any, buffer: Any, src: int, dst: int, src_stage: int, dst_stage: int) -> None:
        vk = self.device.vk
        barrier = vk.VkBufferMemoryBarrier(
            srcAccessMask=src,
            dstAccessMask=dst,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            buffer=buffer.handle,
            offset=0,
            size=buffer.size,
        )
        vk.vkCmdPipelineBarrier(cb, src_stage, dst_stage, 0, 0, None, 1, [barrier], 0, None)

    def destroy(self) -> None:
        vk = self.device.vk
        if self.pipeline is not None:
            vk.vkDestroyPipeline(self.device.handle, self.pipeline, None)
        vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)


class LightCulling:
    """The renderer's choice between the all-lights loop and clusters, frame by frame, and the
    cluster pass. `plan` says whether the pipelines must change; `check_peak` reads back, once a
    frame slot is free again, how full its fullest cluster was."""

    def __init__(self, device: Device, frame_set_layout: Any, mode: str = "auto") -> None:
        check_light_culling(mode)
        self.mode = mode  # auto | loop | clustered
        self.clustered = False  # the mesh pipelines loop over cluster lists
        self.overflow = 0  # lights in the fullest cluster, once one held more than its list keeps
        self.pool = 0  # the index pool's capacity once grown (0: the grid's first size)
        self.pass_ = ClusterPass(device, frame_set_layout)

    def plan(self, data: Any, width: int, height: int) -> tuple[ClusterGrid | None, bool]:
        """(this frame's grid or None, whether `clustered` changed)."""
        clustered = False
        reach = 0.0
        if self.mode != "loop" and (
            self.clustered or self.mode == "clustered" or data.light_count >= CLUSTER_MIN_LIGHTS // 2
        ):
            bounded, unbounded, reach = light_census(data.lights, data.directional, data.camera.position)
            clustered = wants_clusters(self.mode, self.clustered, bounded, unbounded)
            clustered &= not (self.overflow and self.mode == "auto")
        flipped = clustered != self.clustered
        self.clustered = clustered
        grid = cluster_grid(width, height, data.camera.near, reach, self.pool) if clustered else None
        if grid is not None and not self.pool:
            self.pool = grid.pool_capacity
        return grid, flipped

    def check_peak(self, frame: Any) -> None:
        """A cluster that held more lights than its list keeps dropped some (that frame was drawn
        without them): warn once; `auto` draws with the all-lights loop from then on."""
        found = frame.last_cluster_peak()
        if found is None:
            return
        peak, used = found
        if used > self.pool:  # lists were cut short that frame: a bigger pool from now on
            self.pool = 1 << int(used * 1.25).bit_length()
            log.debug("light cluster pool grown to %d indices (%d were asked for)", self.pool, used)
        if peak > MAX_CLUSTER_LIGHTS and not self.overflow:
            self.overflow = peak
            log.warning(
                "%d lights reach one light cluster, more than the %d it lists; %s",
                peak,
                MAX_CLUSTER_LIGHTS,
                "drawing with the all-lights loop" if self.mode == "auto" else "some are left out",
            )

    def record(self, cb: Any, frame: Any, grid: ClusterGrid) -> None:
        self.pass_.record(cb, frame.set_array, grid, frame.clusters, frame.cluster_peak)

    def destroy(self) -> None:
        self.pass_.destroy()
