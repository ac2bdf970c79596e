"""ECS workload query_overhead: the fixed cost of a query per matched table.

A native query costs per matched table (archetype), not per entity, so a world of many small
archetypes is its worst case: 256 tables of 4 entities each. us_per_table is the time per
matched table of `for b in world.query(Position): b[Position].x`; floor_us_per_table slices the
same columns straight from the tables, the cost of the Python loop alone, so the difference is
what the query machinery adds.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable

from ecs_engine import Component, World

from .ecs_components import NPosition
from .ecs_harness import Runner


def run_overhead(r: Runner) -> None:
    tables, per = r.sizes.archetypes, r.sizes.rows_per_archetype
    with r.progress.step(f"query over {tables} archetypes [native]"):
        world = World()
        for i in range(tables):
            tag = type(f"Tag{i}", (Component,), {})
            world.spawn_batch(per, NPosition(), tag())
        matched = world.query(NPosition).tables
        if len(matched) != tables:
            raise RuntimeError(f"expected {tables} matched tables, got {len(matched)}")

        def iterate() -> None:
            for b in world.query(NPosition):
                b[NPosition].x  # noqa: B018 - the column access is what is timed

        key = (NPosition, "x")

        def floor() -> None:
            for t in matched:
                if t.count:
                    t.columns[key][: t.count]

        def best_of(fn: Callable[[], None]) -> float:
            fn()
            t0 = time.perf_counter()
            fn()
            once = max(time.perf_counter() - t0, 1e-7)
            reps = max(1, min(2000, int(0.02 / once)))
            best = math.inf
            gc.collect()
            for _ in range(r.sizes.overhead_repeats):
                t0 = time.perf_counter()
                for _ in range(reps):
                    fn()
                best = min(best, (time.perf_counter() - t0) / reps)
            return best

        sec = best_of(iterate)
        r.row(
            "query_overhead",
            tables * per,
            "native",
            sec,
            tables * per,
            tables=tables,
            us_per_table=sec / tables * 1e6,
            floor_us_per_table=best_of(floor) / tables * 1e6,
        )
