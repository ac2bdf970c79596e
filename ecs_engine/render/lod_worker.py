"""Levels of detail built in a child process, for windowed sessions: the window keeps drawing (the
mesh at full detail) while a big model's levels are made, and they are swapped in when ready.

Why a process, not a thread of the job pool: fast-simplification holds the GIL for each whole
simplification (about a second a level at 263k vertices on the 2-core box), so a thread still
stalled the frame loop: measured with a build in a thread, the main thread's longest wait was
2.2 s at 66k vertices and 2.8 s at 263k, 5.5 and 8.7 s in all. A child process costs about 2 s
to start (once, on the first big mesh) and a copy of the mesh each way.

Headless runs (tests, screenshots, benchmarks) build on the calling thread instead, so a frame's
image does not depend on when a build finished (mesh_registry.py)."""

from __future__ import annotations

import dataclasses
import multiprocessing
from concurrent.futures import Future, ProcessPoolExecutor

from .layouts import MAX_LODS
from .mesh_data import MeshData
from .mesh_lod import Lod, build_lods

__all__ = ["LevelBuilder"]


def _build(mesh: MeshData) -> list[Lod]:
    """In the child: the levels the registry keeps."""
    return build_lods(mesh)[:MAX_LODS]


def _received(lods: list[Lod]) -> list[Lod]:
    """Levels as they come back: MeshData's arrays are made read-only again (pickling drops that)."""
    return [dataclasses.replace(lod, mesh=dataclasses.replace(lod.mesh)) for lod in lods]


class LevelBuilder:
    """One child process, started on the first submit; builds run one at a time, in order."""

    def __init__(self) -> None:
        self._pool: ProcessPoolExecutor | None = None
        self._pending: dict[int, Future[list[Lod]]] = {}

    def submit(self, key: int, mesh: MeshData) -> None:
        if key in self._pending:
            return
        if self._pool is None:
            # spawn: a fork would copy the Vulkan device and the worker threads' locks
            self._pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
        self._pending[key] = self._pool.submit(_build, mesh)

    def pending(self, key: int) -> bool:
        return key in self._pending

    def finished(self) -> list[tuple[int, list[Lod]]]:
        """The builds done since the last call (without waiting); a build that failed raises here."""
        done = [key for key, future in self._pending.items() if future.done()]
        return [(key, _received(self._pending.pop(key).result())) for key in done]

    def wait(self, key: int) -> list[Lod]:
        return _received(self._pending.pop(key).result())

    def close(self) -> None:
        """Drop the builds not started and end the child (a build under way is not waited for)."""
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
        self._pending.clear()
