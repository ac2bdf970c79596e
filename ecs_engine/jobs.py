"""The worker pool: persistent threads, created once, that run jobs over chunks of rows.

Threads only pay when a job runs without the GIL (numba nogil kernels, large NumPy operations),
so jobs are whole chunks, never single entities. With one thread everything runs inline on the
calling thread. A job that raises is re-raised on the calling thread naming its chunk, after
every other job of the batch has finished (no job is left running against freed data).

A batch costs little to hand out, because a frame hands out several (motion, transforms, render
jobs) and at 16 threads concurrent.futures cost ~0.36 ms a batch on the GPU host. Here the
calling thread wakes each helper by releasing its lock and the threads take chunk indices from
one shared counter: no future or queue item per chunk, and a thread that starts late takes
fewer chunks.

A pool with a `timer` (JobTimer: the app's profiler, while a trace is recorded or someone looks
at the figures) reports each job's run from the thread that ran it, named as in errors; without
one a batch pays one attribute test.
"""

from __future__ import annotations

import itertools
import os
import threading
from collections.abc import Callable, Sequence
from time import perf_counter_ns
from typing import Any, Generic, Protocol, TypeVar

T = TypeVar("T")
R = TypeVar("R")

Names = Sequence[str] | Callable[[Any], str] | None


class JobTimer(Protocol):
    """What a pool reports each job's run to, from the thread that ran it."""

    def job(self, name: str, start_ns: int, end_ns: int) -> None: ...


class JobError(RuntimeError):
    """A job failed; the message names its chunk, the cause is chained."""


def default_threads() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


class _Batch(Generic[T, R]):
    """One map call: chunks handed out by a shared counter (next() on itertools.count is atomic
    under the GIL); the last helper to run out of chunks releases `done`."""

    def __init__(self, fn: Callable[[T], R], chunks: Sequence[T], names: Names, helpers: int) -> None:
        self.fn, self.chunks, self.names, self.helpers = fn, chunks, names, helpers
        self.results: list[Any] = [None] * len(chunks)
        self.errors: dict[int, BaseException] = {}
        self._next = itertools.count()
        self._finished = itertools.count(1)
        self.done = threading.Lock()
        self.done.acquire()

    def work(self) -> None:
        n = len(self.chunks)
        while (i := next(self._next)) < n:
            try:
                self.results[i] = _call(self.fn, self.chunks[i], i, self.names)
            except BaseException as exc:
                self.errors[i] = exc

    def help(self) -> None:
        try:
            self.work()
        finally:
            if next(self._finished) == self.helpers:
                self.done.release()


class JobPool:
    """One per run, shared by the world (a resource) and the renderer; `resize` changes the
    thread count in place, so everything holding the pool sees the new count. `timer`: where
    each job's run is reported (None: not timed)."""

    timer: JobTimer | None = None

    def __init__(self, threads: int | None = None) -> None:
        self._batch: _Batch[Any, Any] | None = None
        self._busy = threading.Lock()  # held by the map call in progress
        self._wakes: list[threading.Lock] = []
        self._workers: list[threading.Thread] = []
        self.threads = 1
        self.generation = 0  # bumped when the threads are replaced (per-thread resources elsewhere may go)
        self.resize(default_threads() if threads is None else threads)

    def resize(self, threads: int) -> None:
        """Run with `threads` threads (counting the caller's) from the next map on."""
        threads = int(threads)
        if threads < 1:
            raise ValueError(f"threads must be at least 1, got {threads}")
        if threads == self.threads and len(self._workers) == threads - 1:
            return
        self.close()
        self.threads = threads
        self.generation += 1
        for k in range(threads - 1):
            wake = threading.Lock()
            wake.acquire()
            worker = threading.Thread(target=self._work, args=(wake,), name=f"ecs-job-{k}", daemon=True)
            self._wakes.append(wake)
            self._workers.append(worker)
            worker.start()

    def _work(self, wake: threading.Lock) -> None:
        while True:
            wake.acquire()  # blocks without the GIL until map() (or close()) releases it
            batch = self._batch
            if batch is None:
                return
            batch.help()

    def map(self, fn: Callable[[T], R], chunks: Sequence[T], names: Names = None) -> list[R]:
        """fn(chunk) for every chunk, in parallel; results in chunk order. The calling thread
        works too, so `threads` counts it. `names` (a list, or a function of the chunk, called
        only when its job fails) name chunks in errors. A map called from inside a job (or
        from a second thread while one runs) runs its chunks inline on the caller."""
        if not chunks:
            return []
        if self.timer is not None:
            fn = _timed(fn, chunks, names, self.timer)
        if not self._workers or len(chunks) == 1 or not self._busy.acquire(blocking=False):
            return [_call(fn, c, i, names) for i, c in enumerate(chunks)]
        try:
            helpers = min(len(self._workers), len(chunks) - 1)
            batch = self._batch = _Batch(fn, chunks, names, helpers)
            for wake in self._wakes[:helpers]:
                wake.release()
            batch.work()
            batch.done.acquire()  # every helper has finished: no job outlives the call
        finally:
            self._batch = None
            self._busy.release()
        if batch.errors:
            raise batch.errors[min(batch.errors)]
        return batch.results

    def close(self) -> None:
        if not self._workers:
            return
        with self._busy:
            self._batch = None
            for wake in self._wakes:
                wake.release()
            for worker in self._workers:
                worker.join()
        self._workers, self._wakes = [], []

    def __enter__(self) -> JobPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _timed(fn: Callable[[T], R], chunks: Sequence[T], names: Names, timer: JobTimer) -> Callable[[T], R]:
    """`fn` reporting each call to `timer`, named as its chunk is in errors (unnamed: the
    function's name and the chunk's index)."""
    label = getattr(fn, "__name__", "job")
    index = {id(c): i for i, c in enumerate(chunks)}

    def timed(chunk: T) -> R:
        start = perf_counter_ns()
        try:
            return fn(chunk)
        finally:
            i = index.get(id(chunk), 0)
            name = f"{label} #{i}" if names is None else names(chunk) if callable(names) else names[i]
            timer.job(name, start, perf_counter_ns())

    return timed


def _call(fn: Callable[[T], R], chunk: T, i: int, names: Names) -> R:
    try:
        return fn(chunk)
    except JobError:
        raise
    except Exception as exc:
        name = f"#{i}" if names is None else names(chunk) if callable(names) else names[i]
        raise JobError(f"job for chunk {name} failed: {type(exc).__name__}: {exc}") from exc


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
