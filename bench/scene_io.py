"""Saved scenes: World.save and World.load of the scaling scene's components, 10k to 1M entities.

The scene is N entities with Transform, Velocity, AngularVelocity and Mesh (Mesh brings
ModelMatrix): what the scaling demo spawns. Each count is saved and loaded three times; the
medians are reported with the file size. The target: 1M entities in under 1 s each way.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine import World
from ecs_engine.components import AngularVelocity, Mesh, Transform, Velocity

THREADS = 1


def scene(n: int) -> World:
    rng = np.random.default_rng(7)
    world = World()
    world.spawn_batch(
        n,
        Transform(position=rng.uniform(-50, 50, (n, 3)), rotation=rng.normal(size=(n, 4))),
        Velocity(linear=rng.normal(size=(n, 3))),
        AngularVelocity(angular=rng.normal(size=(n, 3))),
        Mesh(handle=0),
    )
    return world


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--counts", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    counts = [1_000, 5_000] if args.quick else args.counts
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "bench.scene"
        for n in counts:
            world = scene(n)
            saves, loads = [], []
            with progress.step(f"{n:,} entities"):
                for _ in range(3):
                    t0 = time.perf_counter()
                    world.save(path)
                    t1 = time.perf_counter()
                    loaded = World.load(path)
                    t2 = time.perf_counter()
                    saves.append(t1 - t0)
                    loads.append(t2 - t1)
                    assert len(loaded) == n
            rows.append(
                {
                    "entities": n,
                    "save_s": round(statistics.median(saves), 4),
                    "load_s": round(statistics.median(loads), 4),
                    "file_mb": round(path.stat().st_size / 1e6, 2),
                }
            )
    print("entities    save s   load s   file MB")
    for r in rows:
        print(f"{r['entities']:>9,}  {r['save_s']:7.3f}  {r['load_s']:7.3f}  {r['file_mb']:8.1f}")
    return {"benchmark": "scene-io", "machine": machine, "quick": bool(args.quick), "rows": rows}
