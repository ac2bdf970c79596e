"""ECS workload transform_frame: one frame of motion and transform matrices, the engine's hot path.

Native runs Schedule(MotionSystem, TransformSystem) on one thread, on all threads (native-mt)
and, in a subprocess with ECS_ENGINE_NO_NUMBA=1 (numba's switch is read at import time), with
the NumPy fallback kernels (native-numpy); esper and the adapter run the plain-Python processors
of ecs_components. Before timing, a few entities run in both engines and their matrices are
compared, so the speed-ups are for the same work. This module is also the subprocess:
`python -m bench.ecs_transform --worker JSON`.
"""

from __future__ import annotations

import gc
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine import Schedule, World, native
from ecs_engine.components import (
    AngularVelocity,
    Mesh,
    ModelMatrix,
    NormalMatrix,
    Transform,
    Velocity,
)
from ecs_engine.jobs import JobPool, default_threads
from ecs_engine.systems import MotionSystem, TransformSystem

from .ecs_components import (
    MotionProcessor,
    PAngularVelocity,
    PMesh,
    PModelMatrix,
    PTransform,
    PVelocity,
    TransformProcessor,
)
from .ecs_engines import esper, esper_world
from .ecs_harness import TINY, Runner, Sizes

DT = 1.0 / 60.0
ROOT = Path(__file__).resolve().parent.parent


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
    for p, q, s, v, a in zip(
        data["position"].tolist(),
        data["rotation"].tolist(),
        data["scale"].tolist(),
        data["linear"].tolist(),
        data["angular"].tolist(),
    ):
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
    return {
        "seconds": statistics.median(times),
        "frames": frames,
        "warmup": warmup,
        "threads": threads,
        "first_frame_seconds": first,
        "numba": native.AVAILABLE,
        "min_seconds": min(times),
    }


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
    return {"seconds": statistics.median(times), "frames": frames, "warmup": warmup, "min_seconds": min(times)}


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
            diff = max(
                diff,
                float(np.abs(mm.model.astype(np.float64) - np.reshape(pm.model, (4, 4))).max()),
                float(np.abs(nm.normal.astype(np.float64) - np.reshape(pm.normal, (3, 3))).max()),
            )
    return diff


def numpy_fallback_rows(sizes: Sizes) -> list[dict[str, Any]] | str:
    """Run the native transform frame in a subprocess with ECS_ENGINE_NO_NUMBA=1."""
    plan = [(n, sizes.transform_warmup, _frame_counts(sizes, n, 1e7)) for n in sizes.entities]
    env = dict(os.environ, ECS_ENGINE_NO_NUMBA="1")
    # Same cwd and the repo root last on the path: an installed ecs_engine must keep winning over
    # the source folder (whose components/ and systems/ only map into ecs_engine when installed).
    env["PYTHONPATH"] = os.pathsep.join([p for p in [env.get("PYTHONPATH")] if p] + [str(ROOT)])
    cmd = [
        sys.executable,
        "-m",
        f"{__package__ or 'bench'}.ecs_transform",
        "--worker",
        json.dumps({"task": "transform", "plan": plan}),
    ]
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
        print(
            f"[ecs worker] transform frame N={n} [native-numpy, numba={native.AVAILABLE}]: "
            f"{time.perf_counter() - t0:.2f} s",
            file=sys.stderr,
            flush=True,
        )
    print(json.dumps({"rows": rows}))


def run_transform(r: Runner) -> None:
    sizes = r.sizes
    if r.esper is not None:
        with r.progress.step("transform check: esper processors vs native systems (64 entities)"):
            diff = check_transform()
            r.checks["transform_max_abs_diff"] = diff
            if not diff < 1e-3:
                raise RuntimeError(f"plain-Python transform disagrees with the engine (max diff {diff})")
    for n in sizes.entities:
        if r.esper is not None:
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


if __name__ == "__main__":
    # Internal: `python -m bench.ecs_transform --worker JSON` (the numpy-fallback subprocess).
    if len(sys.argv) == 3 and sys.argv[1] == "--worker":
        _worker(json.loads(sys.argv[2]))
    else:
        print("use: ecs-engine bench ecs [--quick]", file=sys.stderr)
        sys.exit(2)
