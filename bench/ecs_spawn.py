"""ECS workloads spawn and spawn_10_batches, and the document's memory section.

Creating entities is where a columnar engine pays for its layout up front: spawn times one
spawn_batch of Transform, Velocity and Mesh against esper's create_entity loop, and
spawn_10_batches the same entities in ten calls. The worlds spawned here are then measured:
memory_bytes against the raw column bytes (the layout's overhead, also after ten batches and
after shrink_to_fit) and tracemalloc's bytes per entity for both engines.
"""

from __future__ import annotations

import gc
import statistics
import time
import tracemalloc
from typing import Any

import numpy as np

from ecs_engine import World
from ecs_engine.components import Mesh, Transform, Velocity

from .ecs_components import PMesh, PTransform, PVelocity
from .ecs_engines import esper_world
from .ecs_harness import Runner


def raw_column_bytes(world: World) -> int:
    total = 0
    for table in world.tables:
        for col in table.columns.values():
            total += table.count * col.dtype.itemsize * int(np.prod(col.shape[1:], dtype=np.int64))
    return total


def _spawn_native(world: World, pos: np.ndarray) -> np.ndarray:
    return world.spawn_batch(len(pos), Transform(position=pos), Velocity(), Mesh())


def esper_spawn(api: Any, pos: list[list[float]]) -> float:
    create = api.create_entity
    gc.collect()
    t0 = time.perf_counter()
    for x, y, z in pos:
        create(PTransform(x, y, z), PVelocity(), PMesh())
    return time.perf_counter() - t0


def run_spawn_memory(r: Runner) -> dict[str, Any]:
    n = r.sizes.spawn
    pos = np.random.default_rng(3).uniform(-1000.0, 1000.0, (n, 3))
    memory: dict[str, Any] = {"entities": n}

    with r.progress.step(f"spawn_batch N={n}, 3 fresh worlds [native]"):
        runs = []
        world = None
        for _ in range(3):
            world = None
            gc.collect()
            world = World()
            t0 = time.perf_counter()
            _spawn_native(world, pos)
            runs.append(time.perf_counter() - t0)
        assert world is not None and len(world) == n
        r.row("spawn", n, "native", statistics.median(runs), n, runs=runs)
        memory["memory_bytes"] = world.memory_bytes()
        memory["raw_column_bytes"] = raw_column_bytes(world)
        memory["ratio"] = memory["memory_bytes"] / memory["raw_column_bytes"]
        world = None
        gc.collect()

    with r.progress.step(f"spawn_batch N={n} under tracemalloc [native]"):
        world = World()
        tracemalloc.start()
        before, _ = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        _spawn_native(world, pos)
        after, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        memory["tracemalloc_retained_bytes"] = after - before
        memory["tracemalloc_peak_bytes"] = peak - before
        world = None
        gc.collect()

    k = n // 10
    with r.progress.step(f"10 x spawn_batch N={k} [native]"):
        world = World()
        gc.collect()
        t0 = time.perf_counter()
        for i in range(10):
            _spawn_native(world, pos[i * k : (i + 1) * k])
        elapsed = time.perf_counter() - t0
        r.row("spawn_10_batches", 10 * k, "native", elapsed, 10 * k)
        raw = raw_column_bytes(world)
        b10: dict[str, Any] = {"memory_bytes": world.memory_bytes(), "raw_column_bytes": raw}
        b10["ratio"] = b10["memory_bytes"] / raw
        world.shrink_to_fit()
        b10["memory_bytes_shrunk"] = world.memory_bytes()
        b10["ratio_shrunk"] = b10["memory_bytes_shrunk"] / raw
        memory["batches10"] = b10
        world = None
        gc.collect()

    memory["esper_tracemalloc_bytes_per_entity"] = None
    memory["esper_tracemalloc_entities"] = None
    plist = pos.tolist()
    if r.esper is not None:
        with r.progress.step(f"create_entity loop N={n} [esper]"), esper_world() as api:
            r.row("spawn", n, "esper", esper_spawn(api, plist), n)
        m = min(n, r.sizes.esper_memory_max)
        with r.progress.step(f"create_entity loop N={m} under tracemalloc [esper]"), esper_world() as api:
            tracemalloc.start()
            before, _ = tracemalloc.get_traced_memory()
            esper_spawn(api, plist[:m])
            after, _ = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            memory["esper_tracemalloc_bytes_per_entity"] = (after - before) / m
            memory["esper_tracemalloc_entities"] = m
    r.adapter(f"create_entity loop N={n}", lambda api: r.row("spawn", n, "adapter", esper_spawn(api, plist), n))
    return memory
