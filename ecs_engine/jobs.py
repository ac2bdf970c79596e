"""The worker pool: persistent threads, created once, that run jobs over chunks of rows.

Threads only pay when a job runs without the GIL (numba nogil kernels, large NumPy operations),
so jobs are whole chunks, never single entities. With one thread everything runs inline on the
calling thread. A job that raises is re-raised on the calling thread naming its chunk, after
every other job of the batch has finished (no job is left running against freed data).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any, TypeVar

T = TypeVar("T")
R = TypeVar("R")


class JobError(RuntimeError):
    """A job failed; the message names its chunk, the cause is chained."""


def default_threads() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


class JobPool:
    def __init__(self, threads: int | None = None) -> None:
        self.threads = default_threads() if threads is None else int(threads)
        if self.threads < 1:
            raise ValueError(f"threads must be at least 1, got {self.threads}")
        self._executor = (ThreadPoolExecutor(self.threads - 1, thread_name_prefix="ecs-job")
                          if self.threads > 1 else None)

    def map(self, fn: Callable[[T], R], chunks: Sequence[T],
            names: Sequence[str] | Callable[[T], str] | None = None) -> list[R]:
        """fn(chunk) for every chunk, in parallel; results in chunk order. The calling thread
        works too (it runs the first chunk), so `threads` counts it. `names` (a list, or a
        function of the chunk, called only when its job fails) name chunks in errors."""
        if not chunks:
            return []
        if self._executor is None or len(chunks) == 1:
            return [self._call(fn, c, i, names) for i, c in enumerate(chunks)]
        futures = [self._executor.submit(self._call, fn, c, i, names) for i, c in enumerate(chunks[1:], 1)]
        results: list[Any] = [None] * len(chunks)
        first_error: BaseException | None = None
        try:
            results[0] = self._call(fn, chunks[0], 0, names)
        except BaseException as exc:
            first_error = exc
        for i, fut in enumerate(futures, 1):
            try:
                results[i] = fut.result()
            except BaseException as exc:
                first_error = first_error or exc
        if first_error is not None:
            raise first_error
        return results

    @staticmethod
    def _call(fn: Callable[[T], R], chunk: T, i: int, names: Sequence[str] | Callable[[T], str] | None) -> R:
        try:
            return fn(chunk)
        except JobError:
            raise
        except Exception as exc:
            name = f"#{i}" if names is None else names(chunk) if callable(names) else names[i]
            raise JobError(f"job for chunk {name} failed: {type(exc).__name__}: {exc}") from exc

    def close(self) -> None:
        if self._executor is not None:
            self._executor.shutdown(wait=True)
            self._executor = None

    def __enter__(self) -> JobPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def row_chunks(count: int, chunk_rows: int) -> list[slice]:
    """Split `count` rows into slices of about `chunk_rows` (the last one may be shorter)."""
    if count <= 0:
        return []
    chunk_rows = max(1, chunk_rows)
    return [slice(start, min(start + chunk_rows, count)) for start in range(0, count, chunk_rows)]


# Below this many rows a table is processed in one piece: a job costs tens of microseconds to
# hand out, about what the kernels need for 10k rows.
CHUNK_ROWS = 16_384


def over_rows(pool: JobPool | None, count: int, fn: Callable[[slice], Any], chunk_rows: int = CHUNK_ROWS) -> None:
    """Run fn(row_slice) over `count` rows: whole on this thread when small or without a pool,
    else in about one chunk per thread."""
    if pool is None or pool.threads == 1 or count < 2 * chunk_rows:
        fn(slice(0, count))
        return
    per = max(chunk_rows, -(-count // pool.threads))
    chunks = row_chunks(count, per)
    pool.map(fn, chunks, [f"rows {c.start}:{c.stop}" for c in chunks])
