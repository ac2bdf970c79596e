"""ECS benchmark: esper 3.x against ecs_engine's native API (and its esper adapter, if present).

Run: `python -m bench ecs [--quick] [--out DIR] [--machine SLUG]`. Everything runs in this one
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
                  transform_math._angular_kernel; 4x4 camera-relative model matrix as a tuple of 16
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
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import itertools
import json
import math
import os
import statistics
import subprocess
import sys
import time
import tracemalloc
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from ecs_engine.components import (
    AngularVelocity,
    Mesh,
    ModelMatrix,
    NormalMatrix,
    Transform,
    Velocity,
)
from ecs_engine.systems import MotionSystem, TransformSystem

import ecs_engine
from ecs_engine import Component, Field, Schedule, World, native
from ecs_engine.jobs import JobPool, default_threads

try:
    import esper
except ImportError:  # pragma: no cover - esper is a dev/bench extra
    esper = None  # type: ignore[assignment]
if esper is not None and not hasattr(esper, "switch_world"):  # pragma: no cover - esper 2.x
    esper = None  # type: ignore[assignment]

THREADS = default_threads()  # the most any row uses (native-mt); each row records its own
SCHEMA_VERSION = 1
DT = 1.0 / 60.0
ROOT = Path(__file__).resolve().parent.parent


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


FULL = Sizes(entities=[10_000, 100_000, 1_000_000], query_runs=20, frames=500, transform_warmup=3,
             transform_max_frames=50, spawn=1_000_000)
QUICK = Sizes(entities=[1_000, 5_000], query_runs=20, frames=100, transform_warmup=2,
              transform_max_frames=5, spawn=100_000)
# Test knob (--tiny, hidden): the smallest run that still exercises every code path.
TINY = Sizes(entities=[300], query_runs=3, frames=20, transform_warmup=1, transform_max_frames=2,
             spawn=2_000, overhead_repeats=2, esper_memory_max=1_000)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--tiny", action="store_true", help=argparse.SUPPRESS)


# ============================================================== components
# esper's benchmark components (plain classes), x/y settable so sums can be checked.
class EPosition:
    def __init__(self, x: float = 0.0, y: float = 0.0) -> None:
        self.x = x
        self.y = y


class EVelocity:
    def __init__(self, x: float = 0.0, y: float = 0.0) -> None:
        self.x = x
        self.y = y


class EHealth:
    def __init__(self) -> None:
        self.hp = 100


class ECommand:
    def __init__(self) -> None:
        self.attack = False
        self.defend = True


class EDamageable:
    def __init__(self) -> None:
        self.defense = 45


# The same as native schemas.
class NPosition(Component):
    x = Field(np.float64)
    y = Field(np.float64)


class NVelocity(Component):
    x = Field(np.float64)
    y = Field(np.float64)


class NHealth(Component):
    hp = Field(np.int32, default=100)


class NCommand(Component):
    attack = Field(np.bool_, default=False)
    defend = Field(np.bool_, default=True)


class NDamageable(Component):
    defense = Field(np.int32, default=45)


# Plain-Python transform components for the esper frame (fastest honest plain Python: slots).
class PTransform:
    __slots__ = ("x", "y", "z", "qx", "qy", "qz", "qw", "sx", "sy", "sz")

    def __init__(self, x: float = 0.0, y: float = 0.0, z: float = 0.0, qx: float = 0.0,
                 qy: float = 0.0, qz: float = 0.0, qw: float = 1.0, sx: float = 1.0,
                 sy: float = 1.0, sz: float = 1.0) -> None:
        self.x, self.y, self.z = x, y, z
        self.qx, self.qy, self.qz, self.qw = qx, qy, qz, qw
        self.sx, self.sy, self.sz = sx, sy, sz


class PVelocity:
    __slots__ = ("x", "y", "z")

    def __init__(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> None:
        self.x, self.y, self.z = x, y, z


class PAngularVelocity:
    __slots__ = ("x", "y", "z")

    def __init__(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> None:
        self.x, self.y, self.z = x, y, z


class PMesh:
    __slots__ = ("handle", "material")

    def __init__(self, handle: int = 0, material: int = 0) -> None:
        self.handle, self.material = handle, material


_IDENTITY4 = (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)
_IDENTITY3 = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


class PModelMatrix:
    __slots__ = ("model", "normal")

    def __init__(self) -> None:
        self.model = _IDENTITY4
        self.normal = _IDENTITY3


_ProcessorBase: type = esper.Processor if esper is not None else object


class MotionProcessor(_ProcessorBase):  # type: ignore[misc, valid-type]
    """MotionSystem in plain Python: linear step, then the exact constant-rate quaternion step."""

    def __init__(self, api: Any) -> None:
        self.api = api

    def process(self, dt: float) -> None:
        get_components = self.api.get_components
        for _, (t, v) in get_components(PTransform, PVelocity):
            t.x += v.x * dt
            t.y += v.y * dt
            t.z += v.z * dt
        sqrt, sin, cos = math.sqrt, math.sin, math.cos
        for _, (t, a) in get_components(PTransform, PAngularVelocity):
            ax, ay, az = a.x, a.y, a.z
            rate = sqrt(ax * ax + ay * ay + az * az)
            half = 0.5 * rate * dt
            k = sin(half) / rate if rate > 1e-12 else 0.5 * dt
            dx, dy, dz, dw = ax * k, ay * k, az * k, cos(half)
            x, y, z, w = t.qx, t.qy, t.qz, t.qw
            nx = dw * x + dx * w + dy * z - dz * y
            ny = dw * y - dx * z + dy * w + dz * x
            nz = dw * z + dx * y - dy * x + dz * w
            nw = dw * w - dx * x - dy * y - dz * z
            norm = sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
            if norm == 0.0:
                norm = 1.0
            t.qx = nx / norm
            t.qy = ny / norm
            t.qz = nz / norm
            t.qw = nw / norm


class TransformProcessor(_ProcessorBase):  # type: ignore[misc, valid-type]
    """TransformSystem in plain Python: camera-relative model matrix and cofactor normal matrix."""

    def __init__(self, api: Any, origin: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
        self.api = api
        self.origin = origin

    def process(self, dt: float) -> None:
        ox, oy, oz = self.origin
        for _, (t, m) in self.api.get_components(PTransform, PModelMatrix):
            x, y, z, w = t.qx, t.qy, t.qz, t.qw
            n2 = x * x + y * y + z * z + w * w
            s = 2.0 / n2 if n2 > 0.0 else 0.0
            xs, ys, zs = x * s, y * s, z * s
            wx, wy, wz = w * xs, w * ys, w * zs
            xx, xy, xz = x * xs, x * ys, x * zs
            yy, yz, zz = y * ys, y * zs, z * zs
            r00 = 1.0 - (yy + zz)
            r01 = xy - wz
            r02 = xz + wy
            r10 = xy + wz
            r11 = 1.0 - (xx + zz)
            r12 = yz - wx
            r20 = xz - wy
            r21 = yz + wx
            r22 = 1.0 - (xx + yy)
            sx, sy, sz = t.sx, t.sy, t.sz
            m.model = (r00 * sx, r01 * sy, r02 * sz, t.x - ox,
                       r10 * sx, r11 * sy, r12 * sz, t.y - oy,
                       r20 * sx, r21 * sy, r22 * sz, t.z - oz,
                       0.0, 0.0, 0.0, 1.0)
            c0 = sy * sz
            c1 = sx * sz
            c2 = sx * sy
            a0 = c0 if c0 >= 0.0 else -c0
            a1 = c1 if c1 >= 0.0 else -c1
            a2 = c2 if c2 >= 0.0 else -c2
            peak = a0 if a0 >= a1 else a1
            if a2 > peak:
                peak = a2
            if peak > 0.0:
                f = 1.0 / peak
                if sx * sy * sz < 0.0:
                    f = -f
            else:
                f = 0.0
            c0 *= f
            c1 *= f
            c2 *= f
            m.normal = (r00 * c0, r01 * c1, r02 * c2,
                        r10 * c0, r11 * c1, r12 * c2,
                        r20 * c0, r21 * c1, r22 * c2)


# ============================================================== worlds
_world_names = itertools.count()


@contextlib.contextmanager
def esper_world() -> Iterator[Any]:
    """A fresh esper world context (the module API works on the current one)."""
    assert esper is not None
    name = f"bench-ecs-{next(_world_names)}"
    esper.switch_world(name)
    esper.clear_database()
    try:
        yield esper
    finally:
        esper.clear_database()
        esper.switch_world("default")
        esper.delete_world(name)
        gc.collect()


def adapter_class() -> tuple[Any, str | None]:
    """(EsperWorld, None) if ecs_engine.esper_compat imports, else (None, reason)."""
    try:
        from ecs_engine.esper_compat import EsperWorld  # type: ignore[import-not-found]
    except Exception as exc:
        return None, f"{type(exc).__name__}: {exc}"
    return EsperWorld, None


@contextlib.contextmanager
def adapter_world(cls: Any) -> Iterator[Any]:
    world = cls()
    try:
        yield world
    finally:
        del world
        gc.collect()


class Runner:
    """Collects rows, errors and the adapter's state; one per benchmark run."""

    def __init__(self, sizes: Sizes, progress: Any) -> None:
        self.sizes = sizes
        self.progress = progress
        self.results: list[dict[str, Any]] = []
        self.errors: list[str] = []
        self.adapter_cls, self.adapter_reason = adapter_class()
        self.checks: dict[str, Any] = {"query_sums_match": None, "transform_max_abs_diff": None}

    def row(self, workload: str, entities: int, engine: str, seconds: float, matched: int,
            **extra: Any) -> dict[str, Any]:
        row = {"workload": workload, "entities": int(entities), "engine": engine,
               "seconds": float(seconds),
               "ns_per_entity": float(seconds) / max(int(matched), 1) * 1e9,
               "matched": int(matched)}
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


# ============================================================== 1. esper's queries
def populate_esper(api: Any, n: int, xs: list[float]) -> list[int]:
    create = api.create_entity
    ids = []
    for i in range(n // 2):
        ids.append(create(EPosition(xs[2 * i]), EVelocity(), EHealth(), ECommand()))
        ids.append(create(EPosition(xs[2 * i + 1]), EHealth(), EDamageable()))
    return ids


def populate_native(world: World, n: int, xs: np.ndarray) -> list[int]:
    enemies = world.spawn_batch(n // 2, NPosition(x=xs[0:2 * (n // 2):2], y=0.0), NVelocity(),
                                NHealth(), NCommand())
    things = world.spawn_batch(n // 2, NPosition(x=xs[1:2 * (n // 2):2], y=0.0), NHealth(),
                               NDamageable())
    order = np.empty(2 * (n // 2), dtype=np.int64)
    order[0::2] = enemies
    order[1::2] = things
    return order.tolist()


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


def _time_queries(q1: Callable[[], Any], q2: Callable[[], Any], q3: Callable[[], Any],
                  touch: Callable[[], float], runs: int) -> dict[str, tuple[float, float, float | None]]:
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

    if esper is not None:
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


# ============================================================== 2. dynamic world
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
        r.row("dynamic_world", n, engine, mean, n, frames=frames,
              static_seconds=statistics.fmean(times[:half]) if half else None,
              dynamic_seconds=statistics.fmean(times[half:]))

    if esper is not None:
        with r.progress.step(f"dynamic world N={n}, {frames} frames [esper]"), esper_world() as api:
            gc.collect()
            record("esper", esper_dynamic(api, n, frames))
    with r.progress.step(f"dynamic world N={n}, {frames} frames [native]"):
        record("native", native_dynamic(n, frames))
        gc.collect()
    r.adapter(f"dynamic world N={n}, {frames} frames", lambda api: record("adapter", esper_dynamic(api, n, frames)))


# ============================================================== 3. transform frame
def transform_data(n: int, seed: int = 7) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return {
        "position": rng.uniform(-100.0, 100.0, (n, 3)),
        "rotation": q,
        "scale": rng.uniform(0.5, 2.0, (n, 3)),
        "linear": rng.uniform(-1.0, 1.0, (n, 3)),
        "angular": rng.uniform(-1.0, 1.0, (n, 3)),
    }


def native_transform_world(data: dict[str, np.ndarray]) -> tuple[World, Schedule, np.ndarray]:
    n = len(data["position"])
    world = World()
    ids = world.spawn_batch(
        n,
        Transform(position=data["position"], rotation=data["rotation"], scale=data["scale"]),
        Velocity(linear=data["linear"]),
        AngularVelocity(angular=data["angular"]),
        Mesh(),
        NormalMatrix(),  # the seed's transform made normal matrices too: the same work in both
    )
    schedule = Schedule()
    schedule.add(MotionSystem(), "update")
    schedule.add(TransformSystem(), "post_update")
    return world, schedule, ids


def esper_transform_world(api: Any, data: dict[str, np.ndarray]) -> list[int]:
    create = api.create_entity
    ids = []
    for p, q, s, v, a in zip(data["position"].tolist(), data["rotation"].tolist(), data["scale"].tolist(),
                             data["linear"].tolist(), data["angular"].tolist()):
        ids.append(create(PTransform(*p, *q, *s), PVelocity(*v), PAngularVelocity(*a), PMesh(), PModelMatrix()))
    api.add_processor(MotionProcessor(api), priority=1)
    api.add_processor(TransformProcessor(api), priority=0)
    return ids


def _frame_counts(sizes: Sizes, n: int, per_frame_budget: float) -> int:
    return max(2 if sizes is TINY else 3, min(sizes.transform_max_frames, math.ceil(per_frame_budget / n)))


def native_transform(n: int, warmup: int, frames: int, threads: int = 1) -> dict[str, Any]:
    world, schedule, _ = native_transform_world(transform_data(n))
    pool = world.resources[JobPool] = JobPool(threads)
    t0 = time.perf_counter()
    schedule.run(world, DT)
    first = time.perf_counter() - t0
    for _ in range(warmup - 1):
        schedule.run(world, DT)
    gc.collect()
    times = []
    for _ in range(frames):
        t0 = time.perf_counter()
        schedule.run(world, DT)
        times.append(time.perf_counter() - t0)
    pool.close()
    return {"seconds": statistics.median(times), "frames": frames, "warmup": warmup, "threads": threads,
            "first_frame_seconds": first, "numba": native.AVAILABLE, "min_seconds": min(times)}


def esper_transform(api: Any, n: int, warmup: int, frames: int) -> dict[str, Any]:
    esper_transform_world(api, transform_data(n))
    for _ in range(warmup):
        api.process(DT)
    gc.collect()
    times = []
    for _ in range(frames):
        t0 = time.perf_counter()
        api.process(DT)
        times.append(time.perf_counter() - t0)
    return {"seconds": statistics.median(times), "frames": frames, "warmup": warmup,
            "min_seconds": min(times)}


def check_transform(n: int = 64, frames: int = 3) -> float:
    """Max |difference| of model and normal matrices between esper processors and native systems."""
    assert esper is not None
    data = transform_data(n, seed=99)
    world, schedule, nids = native_transform_world(data)
    for _ in range(frames):
        schedule.run(world, DT)
    with esper_world() as api:
        eids = esper_transform_world(api, data)
        for _ in range(frames):
            api.process(DT)
        diff = 0.0
        for nid, eid in zip(nids.tolist(), eids):
            mm, nm = world.get(nid, ModelMatrix), world.get(nid, NormalMatrix)
            pm = api.component_for_entity(eid, PModelMatrix)
            diff = max(diff, float(np.abs(mm.model.astype(np.float64) - np.reshape(pm.model, (4, 4))).max()),
                       float(np.abs(nm.normal.astype(np.float64) - np.reshape(pm.normal, (3, 3))).max()))
    return diff


def numpy_fallback_rows(sizes: Sizes) -> list[dict[str, Any]] | str:
    """Run the native transform frame in a subprocess with ECS_ENGINE_NO_NUMBA=1."""
    plan = [(n, sizes.transform_warmup, _frame_counts(sizes, n, 1e7)) for n in sizes.entities]
    env = dict(os.environ, ECS_ENGINE_NO_NUMBA="1")
    # Same cwd and the repo root last on the path: an installed ecs_engine must keep winning over
    # the source folder (whose components/ and systems/ only map into ecs_engine when installed).
    env["PYTHONPATH"] = os.pathsep.join([p for p in [env.get("PYTHONPATH")] if p] + [str(ROOT)])
    cmd = [sys.executable, "-m", f"{__package__ or 'bench'}.ecs", "--worker",
           json.dumps({"task": "transform", "plan": plan})]
    proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=None, text=True)
    if proc.returncode != 0:
        return f"numpy-fallback worker exited with {proc.returncode}"
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        return "numpy-fallback worker printed no result"
    return json.loads(lines[-1])["rows"]


def _worker(spec: dict[str, Any]) -> None:
    if spec["task"] != "transform":
        raise SystemExit(f"unknown worker task {spec['task']!r}")
    rows = []
    for n, warmup, frames in spec["plan"]:
        t0 = time.perf_counter()
        res = native_transform(int(n), int(warmup), int(frames))
        res["entities"] = int(n)
        rows.append(res)
        print(f"[ecs worker] transform frame N={n} [native-numpy, numba={native.AVAILABLE}]: "
              f"{time.perf_counter() - t0:.2f} s", file=sys.stderr, flush=True)
    print(json.dumps({"rows": rows}))


def run_transform(r: Runner) -> None:
    sizes = r.sizes
    if esper is not None:
        with r.progress.step("transform check: esper processors vs native systems (64 entities)"):
            diff = check_transform()
            r.checks["transform_max_abs_diff"] = diff
            if not diff < 1e-3:
                raise RuntimeError(f"plain-Python transform disagrees with the engine (max diff {diff})")
    for n in sizes.entities:
        if esper is not None:
            frames = _frame_counts(sizes, n, 1.5e5)
            with r.progress.step(f"transform frame N={n}, {frames} frames [esper]"), esper_world() as api:
                res = esper_transform(api, n, 1, frames)
                r.row("transform_frame", n, "esper", res.pop("seconds"), n, **res)
        frames = _frame_counts(sizes, n, 1e7)
        with r.progress.step(f"transform frame N={n}, {frames} frames [native, numba={native.AVAILABLE}]"):
            res = native_transform(n, sizes.transform_warmup, frames)
            r.row("transform_frame", n, "native", res.pop("seconds"), n, **res)
            gc.collect()
        threads = default_threads()
        if threads > 1:
            with r.progress.step(f"transform frame N={n}, {frames} frames [native, {threads} threads]"):
                res = native_transform(n, sizes.transform_warmup, frames, threads)
                r.row("transform_frame", n, "native-mt", res.pop("seconds"), n, **res)
                gc.collect()

        def adapter_run(api: Any, n: int = n) -> None:
            frames = _frame_counts(sizes, n, 1.5e5)
            res = esper_transform(api, n, 1, frames)
            r.row("transform_frame", n, "adapter", res.pop("seconds"), n, **res)

        r.adapter(f"transform frame N={n}", adapter_run)
    with r.progress.step("transform frame, all N [native-numpy: subprocess, ECS_ENGINE_NO_NUMBA=1]"):
        rows = numpy_fallback_rows(sizes)
    if isinstance(rows, str):
        r.errors.append(rows)
    else:
        for res in rows:
            n = res.pop("entities")
            r.row("transform_frame", n, "native-numpy", res.pop("seconds"), n, **res)


# ============================================================== 4 + 6. spawn and memory
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
            _spawn_native(world, pos[i * k:(i + 1) * k])
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
    if esper is not None:
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


# ============================================================== 5. per-query overhead
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
                b[NPosition].x

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
        r.row("query_overhead", tables * per, "native", sec, tables * per, tables=tables,
              us_per_table=sec / tables * 1e6, floor_us_per_table=best_of(floor) / tables * 1e6)


# ============================================================== report
def ratios(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    by = {(x["workload"], x["entities"], x["engine"]): x["seconds"] for x in results}
    out = []
    for (workload, n, engine), sec in by.items():
        if engine == "esper":
            continue
        base = by.get((workload, n, "esper"))
        if base is not None and sec > 0:
            out.append({"workload": workload, "entities": n, "numerator": "esper", "denominator": engine,
                        "ratio": base / sec})
    return out


def targets(results: list[dict[str, Any]], memory: dict[str, Any]) -> list[dict[str, Any]]:
    out = []

    def add(name: str, target: float, measured: float, unit: str, op: str, entities: int) -> None:
        met = {"<": measured < target, "<=": measured <= target, ">=": measured >= target}[op]
        out.append({"name": name, "target": target, "measured": measured, "unit": unit, "op": op,
                    "met": bool(met), "entities": int(entities)})

    spawn = next(x for x in results if x["workload"] == "spawn" and x["engine"] == "native")
    add("spawn_batch of 1M entities (Transform, Velocity, Mesh)", 1.0,
        spawn["seconds"] * 1_000_000 / spawn["entities"], "s per 1M entities", "<", spawn["entities"])
    ov = next(x for x in results if x["workload"] == "query_overhead")
    add("query overhead per matched table", 5.0, ov["us_per_table"], "us/table", "<", ov["entities"])
    add("memory_bytes / raw column bytes after spawn_batch", 1.5, memory["ratio"], "x", "<=",
        memory["entities"])
    frames = {(x["entities"], x["engine"]): x for x in results if x["workload"] == "transform_frame"}
    n = 100_000 if (100_000, "esper") in frames else max((k[0] for k in frames if k[1] == "esper"), default=0)
    esp = frames.get((n, "esper"))
    for engine, label in (("native", "1 thread"), ("native-mt", "all threads")):
        eng = frames.get((n, engine))
        if esp and eng:
            threads = eng.get("threads", 1)
            add(f"transform frame speed-up over esper ({label}: {threads})", 100.0,
                esp["seconds"] / eng["seconds"], "x", ">=", n)
    return out


_UNITS = {"query1": ("ns/entity", 1.0), "query2": ("ns/entity", 1.0), "query3": ("ns/entity", 1.0),
          "query1_sum_x": ("ns/entity", 1.0), "dynamic_world": ("ms/frame", 1e3),
          "transform_frame": ("ms/frame", 1e3), "spawn": ("s", 1.0), "spawn_10_batches": ("s", 1.0),
          "query_overhead": ("us/table", 1.0)}


def _value(row: dict[str, Any]) -> float:
    unit, scale = _UNITS.get(row["workload"], ("s", 1.0))
    if unit == "ns/entity":
        return row["ns_per_entity"]
    if unit == "us/table":
        return row["us_per_table"]
    return row["seconds"] * scale


def _fmt(v: float | None) -> str:
    if v is None:
        return "-"
    if v >= 100:
        return f"{v:,.0f}"
    if v >= 10:
        return f"{v:.1f}"
    return f"{v:.3g}" if v >= 0.01 else f"{v:.2e}"


def format_table(doc: dict[str, Any]) -> str:
    cells: dict[tuple[str, int], dict[str, dict[str, Any]]] = {}
    for row in doc["results"]:
        cells.setdefault((row["workload"], row["entities"]), {})[row["engine"]] = row
    header = ["workload", "N", "unit", "esper", "engine", "adapter", "esper/engine"]
    lines = [header]
    for (workload, n), engines in cells.items():
        unit = _UNITS.get(workload, ("s", 1.0))[0]
        esp = engines.get("esper")
        variants = [("native", workload)]
        if "native-mt" in engines:
            variants.append(("native-mt", f"{workload} ({engines['native-mt'].get('threads')} threads)"))
        if "native-numpy" in engines:
            variants.append(("native-numpy", f"{workload} (engine numpy fallback)"))
        for engine, label in variants:
            eng = engines.get(engine)
            adp = engines.get("adapter") if engine == "native" else None
            ratio = esp["seconds"] / eng["seconds"] if esp and eng and eng["seconds"] > 0 else None
            lines.append([label, f"{n:,}", unit, _fmt(_value(esp)) if esp else "-",
                          _fmt(_value(eng)) if eng else "-", _fmt(_value(adp)) if adp else "-",
                          f"{ratio:.1f}x" if ratio is not None else "-"])
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    out = []
    for j, line in enumerate(lines):
        out.append("  ".join(c.ljust(w) if i == 0 or i == 2 else c.rjust(w)
                             for i, (c, w) in enumerate(zip(line, widths))))
        if j == 0:
            out.append("  ".join("-" * w for w in widths))
    mem = doc["memory"]
    b10 = mem["batches10"]
    out.append("")
    out.append(f"memory after spawn_batch({mem['entities']:,}): {mem['memory_bytes'] / 1e6:.1f} MB held, "
               f"{mem['raw_column_bytes'] / 1e6:.1f} MB raw columns (x{mem['ratio']:.2f}); tracemalloc: "
               f"{mem['tracemalloc_retained_bytes'] / 1e6:.1f} MB retained, "
               f"{mem['tracemalloc_peak_bytes'] / 1e6:.1f} MB peak")
    out.append(f"memory after 10 spawn_batch calls: x{b10['ratio']:.2f} of raw, x{b10['ratio_shrunk']:.2f} "
               "after shrink_to_fit()")
    if mem["esper_tracemalloc_bytes_per_entity"] is not None:
        native_per = mem["tracemalloc_retained_bytes"] / mem["entities"]
        out.append(f"bytes per entity (tracemalloc): esper {mem['esper_tracemalloc_bytes_per_entity']:.0f}, "
                   f"engine {native_per:.0f}")
    out.append("")
    for t in doc["targets"]:
        out.append(f"target {'MET ' if t['met'] else 'MISS'}  {t['name']}: {t['measured']:.3g} {t['unit']} "
                   f"(target {t['op']} {t['target']:g}, N={t['entities']:,})")
    adapter = doc["adapter"]
    if not adapter["available"]:
        out.append(f"adapter column skipped: ecs_engine.esper_compat not importable ({adapter['reason']})")
    if doc["versions"]["esper"] is None:
        out.append("esper columns skipped: esper is not installed")
    for err in doc["errors"]:
        out.append(f"error: {err}")
    return "\n".join(out)


# ============================================================== schema
_ROW_KEYS = {"workload": str, "entities": int, "engine": str, "seconds": float, "ns_per_entity": float,
             "matched": int}
ENGINES = ("esper", "native", "native-mt", "native-numpy", "adapter")


def validate(doc: dict[str, Any]) -> list[str]:
    """Problems with `doc` against schema_version 1 (empty list: valid)."""
    bad: list[str] = []

    def need(obj: Any, key: str, typ: Any, where: str) -> Any:
        if not isinstance(obj, dict) or key not in obj:
            bad.append(f"{where}: missing {key!r}")
            return None
        val = obj[key]
        if typ is float:
            ok = isinstance(val, (int, float)) and not isinstance(val, bool) and math.isfinite(val)
        elif typ is int:
            ok = isinstance(val, int) and not isinstance(val, bool)
        else:
            ok = isinstance(val, typ)
        if not ok:
            bad.append(f"{where}.{key}: expected {getattr(typ, '__name__', typ)}, got {val!r}")
        return val

    if need(doc, "benchmark", str, "doc") != "ecs":
        bad.append("doc.benchmark must be 'ecs'")
    if doc.get("schema_version") != SCHEMA_VERSION:
        bad.append(f"doc.schema_version must be {SCHEMA_VERSION}")
    need(doc, "quick", bool, "doc")
    machine = need(doc, "machine", dict, "doc") or {}
    for key, typ in (("hostname", str), ("cpu_model", str), ("cpu_affinity", int), ("python", str),
                     ("numpy", str), ("datetime_utc", str), ("threads", int), ("slug", str)):
        need(machine, key, typ, "machine")
    if "gpu" not in machine:
        bad.append("machine: missing 'gpu'")
    need(doc, "versions", dict, "doc")
    adapter = need(doc, "adapter", dict, "doc") or {}
    need(adapter, "available", bool, "adapter")
    need(doc, "config", dict, "doc")
    results = need(doc, "results", list, "doc") or []
    if not results:
        bad.append("doc.results is empty")
    for i, row in enumerate(results):
        for key, typ in _ROW_KEYS.items():
            need(row, key, typ, f"results[{i}]")
        if isinstance(row, dict) and row.get("engine") not in ENGINES:
            bad.append(f"results[{i}].engine: {row.get('engine')!r} not in {ENGINES}")
    for i, ratio in enumerate(need(doc, "ratios", list, "doc") or []):
        for key, typ in (("workload", str), ("entities", int), ("numerator", str), ("denominator", str),
                         ("ratio", float)):
            need(ratio, key, typ, f"ratios[{i}]")
    memory = need(doc, "memory", dict, "doc") or {}
    for key in ("entities", "memory_bytes", "raw_column_bytes"):
        need(memory, key, int, "memory")
    need(memory, "ratio", float, "memory")
    b10 = need(memory, "batches10", dict, "memory") or {}
    for key in ("ratio", "ratio_shrunk"):
        need(b10, key, float, "memory.batches10")
    need(doc, "checks", dict, "doc")
    tlist = need(doc, "targets", list, "doc") or []
    if not tlist:
        bad.append("doc.targets is empty")
    for i, t in enumerate(tlist):
        for key, typ in (("name", str), ("target", float), ("measured", float), ("unit", str), ("op", str),
                         ("met", bool), ("entities", int)):
            need(t, key, typ, f"targets[{i}]")
    need(doc, "errors", list, "doc")
    return bad


# ============================================================== entry point
def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    tiny = bool(getattr(args, "tiny", False))
    sizes = TINY if tiny else QUICK if args.quick else FULL
    r = Runner(sizes, progress)
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
        "versions": {"ecs_engine": ecs_engine.__version__,
                     "esper": getattr(esper, "__version__", None) if esper is not None else None,
                     "numba_enabled": bool(native.AVAILABLE)},
        "adapter": {"available": r.adapter_cls is not None, "reason": r.adapter_reason},
        "config": {k: v for k, v in asdict(sizes).items()
                   if k in ("entities", "query_runs", "frames", "transform_warmup", "spawn", "archetypes",
                            "rows_per_archetype")},
        "results": r.results,
        "ratios": ratios(r.results),
        "memory": memory,
        "checks": r.checks,
        "targets": targets(r.results, memory),
        "errors": r.errors,
    }
    problems = validate(doc)
    if problems:  # a bug in this file: fail loudly rather than write a malformed document
        raise RuntimeError("benchmark document does not match its schema: " + "; ".join(problems))
    print(format_table(doc))
    out = Path(args.out) / f"ecs-{machine['slug']}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    plot(doc, out)
    return doc


def plot(doc: dict[str, Any], path: Path) -> None:
    """Nanoseconds per entity for each workload at its largest size, one bar per engine (log)."""
    from . import pyplot, save_figure

    plt = pyplot()

    rows = doc["results"]
    workloads = [w for w in dict.fromkeys(r["workload"] for r in rows) if w != "query_overhead"]
    engines = list(dict.fromkeys(r["engine"] for r in rows))
    fig, ax = plt.subplots(figsize=(12, 4.6))
    width = 0.8 / max(len(engines), 1)
    labels = []
    for i, w in enumerate(workloads):
        n = max(r["entities"] for r in rows if r["workload"] == w)
        labels.append(f"{w}\n{n:,}")
        for j, e in enumerate(engines):
            hit = [r for r in rows if r["workload"] == w and r["engine"] == e and r["entities"] == n]
            if hit and hit[0]["ns_per_entity"] > 0:
                ax.bar(i + j * width, hit[0]["ns_per_entity"], width, color=f"C{j}", label=e if i == 0 or
                       e not in ax.get_legend_handles_labels()[1] else None)
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(workloads)) + 0.4 - width / 2, labels, fontsize=7)
    ax.set_ylabel("ns per entity (lower is better)")
    ax.set_title("ECS workloads: ecs_engine (native, multi-threaded, NumPy fallback, esper adapter) against esper")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, path)


if __name__ == "__main__":
    # Internal: `python -m bench.ecs --worker JSON` (the numpy-fallback subprocess).
    if len(sys.argv) == 3 and sys.argv[1] == "--worker":
        _worker(json.loads(sys.argv[2]))
    else:
        print("use: python -m bench ecs [--quick]", file=sys.stderr)
        sys.exit(2)
