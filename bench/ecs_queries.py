"""ECS workloads query1, query2, query3 and query1_sum_x: iterating a query, esper against native.

The world and the three queries are esper's examples/benchmark.py: N/2 "enemies" and N/2
"things", then `get_component(Position)`, `get_components(Position, Velocity)` and
`get_components(Position, Damageable, Health)`, best of `query_runs` runs. Native iterates
world.query batches and takes each column view, which is what a native system gets instead of
per-entity objects. query1_sum_x also touches the data (sums Position.x), and the sums of all
engines must agree, so no engine can win by skipping work.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ecs_engine import World

from .ecs_components import (
    EDamageable,
    EHealth,
    EPosition,
    EVelocity,
    NDamageable,
    NHealth,
    NPosition,
    NVelocity,
    populate_esper,
    populate_native,
)
from .ecs_engines import esper_world
from .ecs_harness import Runner


def _time_min(fn: Callable[[], Any], runs: int) -> tuple[float, float]:
    """(min, first) of `runs` timed calls."""
    gc.collect()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times), times[0]


def _xs(n: int) -> np.ndarray:
    return np.random.default_rng(12345).uniform(-1000.0, 1000.0, n)


def esper_queries(api: Any, n: int, xs: list[float], runs: int) -> dict[str, tuple[float, float, float | None]]:
    populate_esper(api, n, xs)
    get_component, get_components = api.get_component, api.get_components

    def q1() -> None:
        for _, _ in get_component(EPosition):
            pass

    def q2() -> None:
        for _, (_, _) in get_components(EPosition, EVelocity):
            pass

    def q3() -> None:
        for _, (_, _, _) in get_components(EPosition, EDamageable, EHealth):
            pass

    def touch() -> float:
        s = 0.0
        for _, pos in get_component(EPosition):
            s += pos.x
        return s

    return _time_queries(q1, q2, q3, touch, runs)


def _time_queries(
    q1: Callable[[], Any], q2: Callable[[], Any], q3: Callable[[], Any], touch: Callable[[], float], runs: int
) -> dict[str, tuple[float, float, float | None]]:
    """(best, first run, checksum) seconds for the three queries and the summing one."""
    out: dict[str, tuple[float, float, float | None]] = {}
    for name, fn in (("query1", q1), ("query2", q2), ("query3", q3)):
        best, first = _time_min(fn, runs)
        out[name] = (best, first, None)
    best, first = _time_min(touch, runs)
    out["query1_sum_x"] = (best, first, touch())
    return out


def native_queries(n: int, xs: np.ndarray, runs: int) -> dict[str, tuple[float, float, float | None]]:
    world = World()
    populate_native(world, n, xs)

    def q1() -> None:
        for b in world.query(NPosition):
            b[NPosition]

    def q2() -> None:
        for b in world.query(NPosition, NVelocity):
            b[NPosition]
            b[NVelocity]

    def q3() -> None:
        for b in world.query(NPosition, NDamageable, NHealth):
            b[NPosition]
            b[NDamageable]
            b[NHealth]

    def touch() -> float:
        s = 0.0
        for b in world.query(NPosition):
            s += float(b[NPosition].x.sum())
        return s

    return _time_queries(q1, q2, q3, touch, runs)


def run_queries(r: Runner, n: int) -> None:
    xs = _xs(n)
    matched = {"query1": 2 * (n // 2), "query2": n // 2, "query3": n // 2, "query1_sum_x": 2 * (n // 2)}
    runs = r.sizes.query_runs
    sums: dict[str, float] = {}

    def record(engine: str, res: dict[str, tuple[float, float, float | None]]) -> None:
        for name, (best, first, total) in res.items():
            extra: dict[str, Any] = {"first_seconds": first, "runs": runs}
            if total is not None:
                extra["sum_x"] = total
                sums[engine] = total
            r.row(name, n, engine, best, matched[name], **extra)

    if r.esper is not None:
        with r.progress.step(f"queries N={n} [esper]"), esper_world() as api:
            record("esper", esper_queries(api, n, xs.tolist(), runs))
    with r.progress.step(f"queries N={n} [native]"):
        record("native", native_queries(n, xs, runs))
        gc.collect()
    r.adapter(f"queries N={n}", lambda api: record("adapter", esper_queries(api, n, xs.tolist(), runs)))
    if len(sums) > 1:
        ref = sums["native"]
        ok = all(math.isclose(v, ref, rel_tol=1e-9, abs_tol=1e-6) for v in sums.values())
        prev = r.checks["query_sums_match"]
        r.checks["query_sums_match"] = ok if prev is None else (prev and ok)
        if not ok:
            r.errors.append(f"query1_sum_x N={n}: sums differ between engines: {sums}")
