"""Text-mode ECS scene: N entities with velocity and spin, the stock motion and transform systems,
a one-line summary each second of wall clock and a closing table of frame times."""

from __future__ import annotations

import time

import numpy as np

from ecs_engine import Schedule, World
from ecs_engine.components import AngularVelocity, Mesh, Transform, Velocity
from ecs_engine.jobs import JobPool
from ecs_engine.systems import MotionSystem, TransformSystem


def build(world: World, n: int, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return world.spawn_batch(
        n,
        Transform(position=rng.uniform(-100, 100, size=(n, 3)), rotation=rng.normal(size=(n, 4))),
        Velocity(linear=rng.normal(size=(n, 3))),
        AngularVelocity(angular=rng.normal(size=(n, 3))),
        Mesh(handle=0),
    )


def main(entities: int, frames: int, threads: int | None = None) -> int:
    world = World()
    pool = world.resources[JobPool] = JobPool(threads)  # the stock systems split large tables over it
    t0 = time.perf_counter()
    build(world, entities)
    spawn_s = time.perf_counter() - t0
    schedule = Schedule()
    schedule.add(MotionSystem())
    schedule.add(TransformSystem(), "post_update")
    schedule.run(world, 1 / 60)  # warm-up: compiles the native kernels
    times = []
    last_report = time.perf_counter()
    for i in range(frames):
        start = time.perf_counter()
        schedule.run(world, 1 / 60)
        now = time.perf_counter()
        times.append(now - start)
        if now - last_report >= 1.0:
            print(f"frame {i + 1}/{frames}: {times[-1] * 1e3:.2f} ms cpu")
            last_report = now
    ms = np.array(times) * 1e3
    print(f"{entities} entities spawned in {spawn_s * 1e3:.1f} ms; {frames} frames of motion + transform:")
    print(
        f"  mean {ms.mean():.2f} ms  min {ms.min():.2f} ms  p99 {np.percentile(ms, 99):.2f} ms  "
        f"({ms.mean() * 1e6 / entities:.1f} ns per entity)"
    )
    print(f"  world memory {world.memory_bytes() / 2**20:.1f} MiB, {pool.threads} threads")
    pool.close()
    return 0
