"""ECS benchmark: esper 3.x against ecs_engine's native API (and its esper adapter, if present).

Run: `ecs-engine bench ecs [--quick] [--out DIR] [--machine SLUG]`. Everything runs in this one
process, single-threaded, except the "numpy fallback" engine rows, which run in a subprocess with
ECS_ENGINE_NO_NUMBA=1 (numba's switch is read at import time).

Engines ("engine" in the JSON rows)
    esper         esper 3.x module API; each run gets a fresh world (esper.switch_world to a new
                  name, esper.clear_database(), then back to "default" and delete_world).
    native        ecs_engine: Component schemas, spawn_batch, world.query batches of column views,
                  Schedule + stock systems (numba kernels when numba is available).
    native-numpy  the native transform frame with ECS_ENGINE_NO_NUMBA=1 (NumPy fallback kernels).
    adapter       ecs_engine.esper_compat.EsperWorld running the same esper-style code as the
                  esper rows (plain-Python components); left out when that module does not import.

Workloads ("workload" in the JSON rows); N = entities in the world
    query1, query2, query3   esper's examples/benchmark.py: N/2 "enemies" (Position, Velocity,
                  Health, Command) and N/2 "things" (Position, Health, Damageable); time
                  `for _, _ in get_component(Position): pass`,
                  `for _, (_, _) in get_components(Position, Velocity): pass`,
                  `for _, (_, _, _) in get_components(Position, Damageable, Health): pass`;
                  min of `query_runs` runs (esper's cache is built by the first run, reported as
                  `first_seconds`). Native: `for b in world.query(...): b[A]; b[B]` (the column
                  views a native system gets instead of per-entity objects).
    query1_sum_x  "query + touch": sum Position.x over matched entities (esper: Python loop
                  adding pos.x; native: NumPy sum of each batch's x column). Sums are checked equal.
    dynamic_world esper's examples/benchmark_cache.py: `frames` frames; each frame queries
                  (Position, Velocity) and (Health, Damageable, Position); in the second half each
                  frame deletes one initial entity and creates one enemy + thing pair, then calls
                  process(). seconds = mean frame time (whole frame, not only the queries);
                  `static_seconds` / `dynamic_seconds` are the means of the two halves. Native
                  uses world.destroy(id) and two world.spawn(...) calls (single-entity API).
                  (esper's script calls create_entities(world, 1), which creates nothing since
                  1 // 2 == 0; we create the pair as intended.)
    transform_frame  N entities with Transform, Velocity, AngularVelocity, Mesh (+ModelMatrix) and
                  NormalMatrix (opt-in since the renderer stopped reading it; kept here so both
                  engines make the same two matrices).
                  Native: Schedule(MotionSystem @update, TransformSystem @post_update),
                  frame = schedule.run(world, 1/60). esper: two processors doing the same work per
                  entity in plain Python (position += v*dt; the exact quaternion step of
                  maths.transform._angular_kernel; 4x4 camera-relative model matrix as a tuple of 16
                  floats, origin 0; 3x3 cofactor normal matrix as a tuple of 9). Components use
                  __slots__; the motion processor keeps MotionSystem's two loops (linear over
                  Transform+Velocity, angular over Transform+AngularVelocity; fusing them saves
                  ~5%). Warm-up frames first (numba compiles on first call), then the median of
                  `frames` timed frames. Before timing, 64 entities are run 3 frames in both
                  engines and their matrices compared (`checks.transform_max_abs_diff`).
    spawn         `spawn` entities with Transform (random positions), Velocity, Mesh: native in
                  one spawn_batch call (median of 3 fresh worlds; `runs` lists all), esper
                  create_entity in a Python loop (objects built in the loop).
    spawn_10_batches  the same entities from ten spawn_batch calls of spawn/10.
    query_overhead  256 archetypes (Position + one of 256 tag components, 4 entities each);
                  `for b in world.query(Position): b[Position].x`; `us_per_table` = time per
                  matched table; `floor_us_per_table` = slicing the same columns straight from
                  the tables (the cost of the Python loop alone).

JSON document (schema_version 1), written to <out>/ecs-<slug>.json:
    benchmark       "ecs"
    schema_version  1
    quick           bool
    machine         dict from bench.machine.describe (includes "slug" and "threads")
    versions        {"ecs_engine", "esper" (null if absent), "numba_enabled" (bool)}
    adapter         {"available": bool, "reason": str | null}
    config          the sizes used: {"entities": [int], "query_runs", "frames", "transform_warmup",
                    "spawn", "archetypes", "rows_per_archetype"}
    results         list of rows, each with at least
                      "workload" str, "entities" int, "engine" str (see above),
                      "seconds" float (per run / per frame / total spawn, see workload),
                      "ns_per_entity" float (seconds / matched entities * 1e9),
                      "matched" int (entities the timed work covered)
                    plus workload-specific keys (first_seconds, frames, static_seconds,
                    dynamic_seconds, runs, us_per_table, floor_us_per_table, tables, numba, ...)
    ratios          list of {"workload", "entities", "numerator" ("esper"), "denominator"
                    ("native" | "native-mt" | "native-numpy" | "adapter"), "ratio" float}: esper seconds divided
                    by the other engine's, so > 1 means faster than esper
    memory          {"entities", "memory_bytes", "raw_column_bytes", "ratio",
                     "tracemalloc_retained_bytes", "tracemalloc_peak_bytes",
                     "batches10": {"memory_bytes", "raw_column_bytes", "ratio",
                                   "memory_bytes_shrunk", "ratio_shrunk"},
                     "esper_tracemalloc_bytes_per_entity" (null without esper),
                     "esper_tracemalloc_entities"}
    checks          {"query_sums_match": bool | null, "transform_max_abs_diff": float | null}
    targets         list of {"name", "target" float, "measured" float, "unit", "op" ("<" | "<=" | ">="),
                    "met" bool, "entities" int}
    errors          list of str (adapter failures are recorded here, not raised)

Modules (each workload has its own; this entry imports them and none of them imports it)
    ecs_engines     esper and the adapter (optional), a fresh world per measurement
    ecs_components  the components and processors both engines run, esper's benchmark world
    ecs_harness     Sizes (FULL, QUICK, TINY) and the Runner that collects rows and errors
    ecs_queries     query1, query2, query3, query1_sum_x
    ecs_dynamic     dynamic_world
    ecs_transform   transform_frame (and the native-numpy subprocess, `-m bench.ecs_transform`)
    ecs_spawn       spawn, spawn_10_batches and the "memory" section
    ecs_overhead    query_overhead
    ecs_report      ratios, targets, the table, the schema check (validate) and the plot
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

import ecs_engine
from ecs_engine import native
from ecs_engine.jobs import default_threads

from .ecs_dynamic import run_dynamic
from .ecs_engines import adapter_class, esper
from .ecs_harness import FULL, QUICK, TINY, Runner, Sizes
from .ecs_overhead import run_overhead
from .ecs_queries import run_queries
from .ecs_report import SCHEMA_VERSION, format_table, plot, ratios, targets, validate
from .ecs_spawn import run_spawn_memory
from .ecs_transform import _worker, run_transform

__all__ = [
    "FULL",
    "QUICK",
    "SCHEMA_VERSION",
    "THREADS",
    "TINY",
    "Runner",
    "Sizes",
    "adapter_class",
    "add_arguments",
    "esper",
    "format_table",
    "plot",
    "ratios",
    "run",
    "targets",
    "validate",
]

THREADS = default_threads()  # the most any row uses (native-mt); each row records its own


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--tiny", action="store_true", help=argparse.SUPPRESS)


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    tiny = bool(getattr(args, "tiny", False))
    sizes = TINY if tiny else QUICK if args.quick else FULL
    r = Runner(sizes, progress, esper, adapter_class())
    if esper is None:
        progress.note("esper is not installed: esper rows are skipped")
    if r.adapter_cls is None:
        progress.note(f"adapter column skipped ({r.adapter_reason})")
    if not native.AVAILABLE:
        progress.note("numba disabled or absent: the native rows use the NumPy fallback")

    for n in sizes.entities:
        run_queries(r, n)
    for n in sizes.entities:
        if n <= sizes.dynamic_max:
            run_dynamic(r, n)
    run_transform(r)
    memory = run_spawn_memory(r)
    run_overhead(r)

    doc: dict[str, Any] = {
        "benchmark": "ecs",
        "schema_version": SCHEMA_VERSION,
        "quick": bool(args.quick or tiny),
        "machine": machine,
        "versions": {
            "ecs_engine": ecs_engine.__version__,
            "esper": getattr(esper, "__version__", None) if esper is not None else None,
            "numba_enabled": bool(native.AVAILABLE),
        },
        "adapter": {"available": r.adapter_cls is not None, "reason": r.adapter_reason},
        "config": {
            k: v
            for k, v in asdict(sizes).items()
            if k
            in ("entities", "query_runs", "frames", "transform_warmup", "spawn", "archetypes", "rows_per_archetype")
        },
        "results": r.results,
        "ratios": ratios(r.results),
        "memory": memory,
        "checks": r.checks,
        "targets": targets(r.results, memory),
        "errors": r.errors,
    }
    problems = validate(doc)
    if problems:  # a bug in the benchmark: fail loudly rather than write a malformed document
        raise RuntimeError("benchmark document does not match its schema: " + "; ".join(problems))
    print(format_table(doc))
    out = Path(args.out) / f"ecs-{machine['slug']}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    plot(doc, out)
    return doc


if __name__ == "__main__":
    # Internal, kept for old callers: `python -m bench.ecs --worker JSON` (the numpy-fallback
    # subprocess now runs `python -m bench.ecs_transform --worker JSON`).
    if len(sys.argv) == 3 and sys.argv[1] == "--worker":
        _worker(json.loads(sys.argv[2]))
    else:
        print("use: ecs-engine bench ecs [--quick]", file=sys.stderr)
        sys.exit(2)
