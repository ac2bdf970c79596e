"""What every ECS workload runs in: the sizes of a run and the Runner that collects its rows.

A workload module gets a Runner and adds rows through `Runner.row` (which derives
ns_per_entity from seconds and the entities matched) and adapter measurements through
`Runner.adapter` (a failure becomes an error line, not an exception). The entry point decides
which engines run and hands that to the Runner: `Runner.esper` is the esper module or None, and
`Runner.adapter_cls` the adapter's world class or None.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .ecs_engines import adapter_world


@dataclass
class Sizes:
    entities: list[int]
    query_runs: int
    frames: int  # dynamic world
    transform_warmup: int
    transform_max_frames: int
    spawn: int
    archetypes: int = 256
    rows_per_archetype: int = 4
    overhead_repeats: int = 7
    esper_memory_max: int = 100_000
    # esper rebuilds its query cache after every structural change, so its dynamic world costs
    # O(N) per frame: ~170 ms/frame at 100k on the GPU host; 500 frames at 1M would take ~15 min.
    dynamic_max: int = 100_000


FULL = Sizes(
    entities=[10_000, 100_000, 1_000_000],
    query_runs=20,
    frames=500,
    transform_warmup=3,
    transform_max_frames=50,
    spawn=1_000_000,
)
QUICK = Sizes(
    entities=[1_000, 5_000], query_runs=20, frames=100, transform_warmup=2, transform_max_frames=5, spawn=100_000
)
# Test knob (--tiny, hidden): the smallest run that still exercises every code path.
TINY = Sizes(
    entities=[300],
    query_runs=3,
    frames=20,
    transform_warmup=1,
    transform_max_frames=2,
    spawn=2_000,
    overhead_repeats=2,
    esper_memory_max=1_000,
)


class Runner:
    """Collects rows, errors and the adapter's state; one per benchmark run. `esper` is the esper
    module (None: no esper rows) and `adapter` what `adapter_class()` returned."""

    def __init__(self, sizes: Sizes, progress: Any, esper: Any, adapter: tuple[Any, str | None]) -> None:
        self.sizes = sizes
        self.progress = progress
        self.esper = esper
        self.results: list[dict[str, Any]] = []
        self.errors: list[str] = []
        self.adapter_cls, self.adapter_reason = adapter
        self.checks: dict[str, Any] = {"query_sums_match": None, "transform_max_abs_diff": None}

    def row(
        self, workload: str, entities: int, engine: str, seconds: float, matched: int, **extra: Any
    ) -> dict[str, Any]:
        row = {
            "workload": workload,
            "entities": int(entities),
            "engine": engine,
            "seconds": float(seconds),
            "ns_per_entity": float(seconds) / max(int(matched), 1) * 1e9,
            "matched": int(matched),
        }
        row.update(extra)
        self.results.append(row)
        return row

    def adapter(self, what: str, fn: Callable[[Any], None]) -> None:
        """Run an adapter measurement; a failure is recorded, not raised."""
        if self.adapter_cls is None:
            return
        with self.progress.step(f"{what} [adapter]"):
            try:
                with adapter_world(self.adapter_cls) as api:
                    fn(api)
            except Exception as exc:
                msg = f"adapter {what}: {type(exc).__name__}: {exc}"
                self.errors.append(msg)
                self.progress.note(f"  FAILED: {msg}")
