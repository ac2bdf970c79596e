"""The parallel schedule: 8 independent stock-style systems over 1M entities, 1 to 16 threads.

Each system integrates its own spring (component pair Spring<i>Position / Spring<i>Velocity: a
numba kernel that releases the GIL, one call per table, like the stock systems' kernels) and
declares what it reads and writes, so no two conflict and a parallel schedule (`Schedule(parallel=
True)`) runs them all at once on the world's JobPool. Measured: the median frame (the whole
schedule) for the sequential schedule and for the parallel one at each thread count; the systems'
results are checked equal between the two.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np

from ecs_engine import native
from ecs_engine.ecs import Component, Field, Schedule, System, World
from ecs_engine.jobs import JobPool, default_threads

THREADS = default_threads()
SYSTEMS = 8


def _make_pair(i: int) -> tuple[type[Component], type[Component]]:
    position = type(f"Spring{i}Position", (Component,), {"x": Field(np.float64, (3,))})
    velocity = type(f"Spring{i}Velocity", (Component,), {"v": Field(np.float64, (3,))})
    return position, velocity


PAIRS = [_make_pair(i) for i in range(SYSTEMS)]


def _spring_numpy(x: np.ndarray, v: np.ndarray, k: float, c: float, dt: float) -> None:
    v += (-k * x - c * v) * dt
    x += v * dt


@native.njit
def _spring_native(x, v, k, c, dt):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    for i in range(x.shape[0]):
        for j in range(3):
            v[i, j] += (-k * x[i, j] - c * v[i, j]) * dt
            x[i, j] += v[i, j] * dt


class SpringSystem(System):
    """Semi-implicit Euler on one component pair (what systems/spring.py does, one pair each)."""

    def __init__(self, i: int) -> None:
        position, velocity = PAIRS[i]
        super().__init__(reads=[], writes=[position, velocity], name=f"spring{i}")
        self.position, self.velocity = position, velocity
        self.k, self.c = 4.0 + i, 0.5

    def run(self, world: World, dt: float) -> None:
        kernel = _spring_native if native.AVAILABLE else _spring_numpy
        for batch in world.query(self.position, self.velocity):
            kernel(batch[self.position].x, batch[self.velocity].v, self.k, self.c, dt)


def make_world(n: int, threads: int) -> World:
    world = World()
    rng = np.random.default_rng(1)
    values = []
    for position, velocity in PAIRS:
        values += [position(x=rng.standard_normal((n, 3))), velocity(v=np.zeros((n, 3)))]
    world.spawn_batch(n, *values)
    world.resources[JobPool] = JobPool(threads)
    return world


def frame_ms(n: int, threads: int, parallel: bool, frames: int) -> tuple[float, np.ndarray]:
    world = make_world(n, threads)
    schedule = Schedule(("update",), parallel=parallel)
    for i in range(SYSTEMS):
        schedule.add(SpringSystem(i))
    schedule.run(world, 1 / 60)  # compile and warm
    times = []
    try:
        for _ in range(frames):
            t0 = time.perf_counter()
            schedule.run(world, 1 / 60)
            times.append((time.perf_counter() - t0) * 1e3)
        state = np.concatenate([world.query(p).column(p.x) for p, _ in PAIRS])  # type: ignore[attr-defined]
    finally:
        world.resources[JobPool].close()
    return statistics.median(times), state


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--entities", type=int, default=1_000_000, help="entities (each has all 8 pairs)")
    parser.add_argument("--frames", type=int, default=30, help="frames timed per configuration")


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    n = 2_000 if args.quick else args.entities
    frames = 3 if args.quick else args.frames
    counts = sorted({c for c in (1, 2, 4, 8, 16) if c <= max(THREADS, 1)} | {min(16, THREADS)})
    rows = []
    with progress.step(f"{n:,} entities, sequential schedule"):
        sequential, reference = frame_ms(n, 1, False, frames)
    rows.append({"schedule": "sequential", "threads": 1, "frame_ms": round(sequential, 3)})
    for threads in counts:
        with progress.step(f"{n:,} entities, parallel schedule, {threads} threads"):
            ms, state = frame_ms(n, threads, True, frames)
        if not np.array_equal(state, reference):
            raise AssertionError(f"the parallel schedule at {threads} threads changed the systems' results")
        rows.append({"schedule": "parallel", "threads": threads, "frame_ms": round(ms, 3)})
    best = min(r["frame_ms"] for r in rows if r["schedule"] == "parallel")
    one = next(r["frame_ms"] for r in rows if r["schedule"] == "parallel" and r["threads"] == 1)
    print(f"{SYSTEMS} independent spring systems over {n:,} entities (median of {frames} frames):")
    for r in rows:
        print(f"  {r['schedule']:10} {r['threads']:3} threads  {r['frame_ms']:9.2f} ms")
    print(f"parallel: {one / best:.1f}x faster at its best thread count than at 1 thread")
    return {
        "benchmark": "schedule",
        "machine": machine,
        "quick": bool(args.quick),
        "entities": n,
        "systems": SYSTEMS,
        "frames": frames,
        "numba": native.AVAILABLE,
        "rows": rows,
        "speedup_best_vs_1_thread": round(one / best, 2),
    }
