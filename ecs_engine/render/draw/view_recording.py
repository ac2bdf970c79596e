"""A chunk's rows culled, written and recorded for several views in one native call (the
camera's and the shadow views', frame_jobs.py), where the views draw with the instanced path
and the native recorder.

Done view by view from Python, one chunk's job makes about five calls that release and take
back the GIL (cull, then per drawn view a write and a record). Measured on the GPU host (100k
entities, 7 chunks, 16 threads, a sun with 4 cascades), the jobs then spent most of their time
waiting for the GIL: a 14k-row write that takes 0.1 ms alone took up to 0.4 ms, a record of a
few draws up to 1.2 ms, and the batch 3 ms. Here the Python side acquires the command buffers
and reads the results; one nogil call does the rest: instance_rows' cull_views kernel, its
counting-sort write per view, and the native recorder's loop per view.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...gpu.functions import handle_int
from ..config import Recorder
from ..extract.frame_data import NOT_RECEIVER, Chunk
from ..layouts import INSTANCE
from .instance_rows import NO_EXTRA, _cull_views_native, _write_keyed
from .path import ChunkResult, FrameInputs

_compiled: dict[int, Any] = {}  # per NativeRecorder (id of its compiled loop): the fused kernel


def fused_kernel(record: Any) -> Any:
    """The nogil kernel around `record` (gpu.native_recorder's compiled per-chunk loop, whose
    entry points are baked in: compiled once per device, about a second, on first use)."""
    found = _compiled.get(id(record))
    if found is not None:
        return found[1]
    import numba

    cull = _cull_views_native
    assert cull is not None, "can_fuse() is False without numba"
    write = _write_keyed
    row_bytes = INSTANCE.size

    def record_views(
        model,
        handle,
        material,
        centers,
        radii,
        planes,
        n_materials,
        misc_zw,
        extra,
        rows,
        rows_addr,
        row_starts,
        keys,
        key_counts,
        cbs,
        layouts,
        pipelines,
        vertex_addr,
        zero_addr,
        index_handles,
        index_counts,
        begin_addrs,
        viewport_addrs,
        scissor_addrs,
        set_addrs,
        out,
    ):  # pragma: no cover - compiled
        # out[v] = (draws, triangles, rows) of view v; returns the first failing VkResult or 0
        cull(model, handle, centers, radii, planes, keys, key_counts)
        for v in range(planes.shape[0]):
            out[v, 0] = 0
            out[v, 1] = 0
            total = 0
            for k in range(key_counts.shape[1]):
                total += key_counts[v, k]
            out[v, 2] = total
            if total == 0:
                continue
            start = row_starts[v]
            write(
                model,
                material,
                keys[v],
                key_counts[v],
                n_materials,
                misc_zw[v],
                rows[8 * start : 8 * (start + total)],
                extra,
            )
            result = record(
                cbs[v],
                layouts[v],
                0,
                row_bytes,
                rows_addr + start * row_bytes,
                True,
                start,
                key_counts[v],
                pipelines[v],
                vertex_addr,
                zero_addr,
                index_handles,
                index_counts,
                begin_addrs[v],
                viewport_addrs[v],
                scissor_addrs[v],
                set_addrs[v],
                out[v],
            )
            if result != 0:
                return result
        return 0

    kernel = numba.njit(nogil=True)(record_views)
    _compiled[id(record)] = (record, kernel)  # the loop kept alive with its id's entry
    return kernel


def can_fuse(paths: list[Any]) -> bool:
    """Whether views drawn by these paths can be recorded in one call: instanced rows in the
    frame's mapped buffer and the native recorder (numba present)."""
    return _cull_views_native is not None and all(
        getattr(p, "instanced", False) and p.recorder == Recorder.NATIVE and p.uses_recorder for p in paths
    )


PathHandles = dict[tuple[int, ...], tuple[list[Any], np.ndarray, np.ndarray]]


def _path_handles(vk: Any, paths: list[Any], kept_by: PathHandles) -> tuple[np.ndarray, np.ndarray]:
    """The paths' pipeline layouts (V,) and pipelines (V, 4) as int64, kept in `kept_by` (the
    caller's: the same from frame to frame, a dozen views a frame) per paths, layouts and
    pipelines (held, so their ids stay theirs)."""
    held = [(p, p.layout, p.pipelines) for p in paths]
    key = tuple(id(x) for h in held for x in h)
    kept = kept_by.get(key)
    if kept is None:
        if len(kept_by) >= 16:  # paths and pipelines made again (hot reload, a new target form)
            kept_by.clear()
        layouts = np.array([handle_int(vk, p.layout) for p in paths], np.int64)
        pipelines = np.array([[handle_int(vk, q) for q in p.pipelines] for p in paths], np.int64)
        kept = kept_by[key] = (held, layouts, pipelines)
    return kept[1], kept[2]


class ViewRecording:
    """One frame's views (FrameInputs after their path's begin_frame) as the kernel's arrays;
    `with_camera`: view 0 is the camera's (jobs may then leave it out); `handles`: the caller's
    PathHandles, kept across its frames."""

    def __init__(
        self,
        paths: list[Any],
        views: list[FrameInputs],
        planes: np.ndarray,
        with_camera: bool,
        handles: PathHandles | None = None,
    ) -> None:
        self.with_camera = with_camera
        recorder = paths[0]._recorder.compiled  # one NativeRecorder per device: every path shares it
        vk = recorder.vk
        self.vk, self.recorder, self.views, self.planes = vk, recorder, views, planes
        self.kernel = fused_kernel(recorder._record)
        states = [v.path_state for v in views]
        self.layouts, self.pipelines = _path_handles(vk, paths, {} if handles is None else handles)
        self.begin_addrs = np.array([s["begin_addr"] for s in states], np.int64)
        self.viewport_addrs = np.array([s["viewport_addr"] for s in states], np.int64)
        self.scissor_addrs = np.array([s["scissor_addr"] for s in states], np.int64)
        self.set_addrs = np.array([s["sets_addr"] for s in states], np.int64)
        self.row_bases = np.array([v.row_base for v in views], np.int64)
        instances = views[0].instances
        self.rows = instances.view(np.uint64).reshape(-1)
        self.rows_addr = instances.ctypes.data
        self.secondaries = paths[0].ctx.secondaries
        self.slot = views[0].slot
        self.n_materials = np.uint32(views[0].material_count)

    def record(self, chunk: Chunk, camera: bool) -> list[ChunkResult]:
        """The chunk in every view (without the camera's unless `camera`); per view a result."""
        first = int(self.with_camera and not camera)
        views = self.views[first:]
        centers, radii, index_counts = views[0].bounds
        cbs = [self.secondaries.acquire(self.slot) for _ in views]
        out = np.empty((len(views), 3), np.int64)
        misc_zw = np.zeros(len(views), np.uint64)
        if first == 0 and chunk.flags & NOT_RECEIVER:
            misc_zw[0] = 1  # the camera's rows: no shadow falls on these (mesh_vertex.glsl)
        r = self.recorder
        result = self.kernel(
            chunk.model,
            chunk.handle,
            chunk.material,
            centers,
            radii,
            self.planes[first:],
            self.n_materials,
            misc_zw,
            NO_EXTRA if chunk.extra is None else chunk.extra,
            self.rows,
            self.rows_addr,
            self.row_bases[first:] + chunk.offset,
            np.empty((len(views), len(chunk.handle)), np.int32),
            np.empty((len(views), 2 * len(index_counts)), np.int64),
            np.array([handle_int(self.vk, cb) for cb in cbs], np.int64),
            self.layouts[first:],
            self.pipelines[first:],
            r._vertex.ctypes.data,
            r._zero.ctypes.data,
            r._index,
            r._counts,
            self.begin_addrs[first:],
            self.viewport_addrs[first:],
            self.scissor_addrs[first:],
            self.set_addrs[first:],
            out,
        )
        if result != 0:
            raise RuntimeError(f"recording a secondary command buffer failed with VkResult {result}")
        return [
            ChunkResult(cb if n else None, int(n), int(draws), int(triangles))
            for cb, (draws, triangles, n) in zip(cbs, out.tolist(), strict=True)
        ]
