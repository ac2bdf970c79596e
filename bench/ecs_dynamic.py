"""ECS workload dynamic_world: queries in a world whose entities change every frame.

esper's examples/benchmark_cache.py: esper caches query results and rebuilds the cache after
every structural change, so the second half of the frames, which each delete one entity and
create two, shows what that costs against the native engine, whose queries match tables, not
entities. seconds is the mean whole-frame time; static_seconds and dynamic_seconds are the means
of the two halves.
"""

from __future__ import annotations

import gc
import statistics
import time
from typing import Any

import numpy as np

from ecs_engine import World

from .ecs_components import (
    ECommand,
    EDamageable,
    EHealth,
    EPosition,
    EVelocity,
    NCommand,
    NDamageable,
    NHealth,
    NPosition,
    NVelocity,
    populate_esper,
    populate_native,
)
from .ecs_engines import esper_world
from .ecs_harness import Runner


def esper_dynamic(api: Any, n: int, frames: int) -> list[float]:
    ids = populate_esper(api, n, [0.0] * n)
    get_components = api.get_components
    half = frames // 2
    times = []
    for frame in range(1, frames + 1):
        t0 = time.perf_counter()
        for _, (_, _) in get_components(EPosition, EVelocity):
            pass
        for _, (_, _, _) in get_components(EHealth, EDamageable, EPosition):
            pass
        if frame > half:
            api.delete_entity(ids[frame - 1])
            api.create_entity(EPosition(), EVelocity(), EHealth(), ECommand())
            api.create_entity(EPosition(), EHealth(), EDamageable())
        api.process()
        times.append(time.perf_counter() - t0)
    return times


def native_dynamic(n: int, frames: int) -> list[float]:
    world = World()
    ids = populate_native(world, n, np.zeros(n))
    half = frames // 2
    times = []
    gc.collect()
    for frame in range(1, frames + 1):
        t0 = time.perf_counter()
        for b in world.query(NPosition, NVelocity):
            b[NPosition]
            b[NVelocity]
        for b in world.query(NHealth, NDamageable, NPosition):
            b[NHealth]
            b[NDamageable]
            b[NPosition]
        if frame > half:
            world.destroy(ids[frame - 1])
            world.spawn(NPosition(), NVelocity(), NHealth(), NCommand())
            world.spawn(NPosition(), NHealth(), NDamageable())
        times.append(time.perf_counter() - t0)
    return times


def run_dynamic(r: Runner, n: int) -> None:
    frames = min(r.sizes.frames, 2 * (n // 2))  # each dynamic frame deletes one initial entity
    half = frames // 2

    def record(engine: str, times: list[float]) -> None:
        mean = statistics.fmean(times)
        r.row(
            "dynamic_world",
            n,
            engine,
            mean,
            n,
            frames=frames,
            static_seconds=statistics.fmean(times[:half]) if half else None,
            dynamic_seconds=statistics.fmean(times[half:]),
        )

    if r.esper is not None:
        with r.progress.step(f"dynamic world N={n}, {frames} frames [esper]"), esper_world() as api:
            gc.collect()
            record("esper", esper_dynamic(api, n, frames))
    with r.progress.step(f"dynamic world N={n}, {frames} frames [native]"):
        record("native", native_dynamic(n, frames))
        gc.collect()
    r.adapter(f"dynamic world N={n}, {frames} frames", lambda api: record("adapter", esper_dynamic(api, n, frames)))
