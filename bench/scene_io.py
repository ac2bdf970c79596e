"""Saved scenes: save_world and load_world of the scaling scene, 10k to 1M entities (CPU only).

The scene is what the scaling demo spawns: N entities with Transform, Velocity, AngularVelocity
and Mesh (which brings ModelMatrix), 0.1% of them a second mesh, materials 0-5, plus the world's
Materials resource; saved and loaded with every stock codec (materials, environment, and the
meshes by reference through a registry), as a session does. Each count is saved and loaded three
times into a new world; the medians (and the best) are reported with the file size. The target:
1M entities in under 1 s each way.
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
from ecs_engine.ecs.scene_file import load_world, save_world
from ecs_engine.render.assets.materials import materials
from ecs_engine.render.assets.mesh_data import MeshData
from ecs_engine.render.assets.primitives import cube_mesh, torus_mesh
from ecs_engine.render.assets.scene_assets import scene_codecs

THREADS = 1
TARGET_S = 1.0


class MeshList(list[MeshData]):
    """A session's mesh registry without the GPU (what the mesh codec needs: [handle] and add)."""

    def add(self, mesh: MeshData) -> int:
        self.append(mesh)
        return len(self) - 1


def scene(n: int) -> tuple[World, MeshList]:
    rng = np.random.default_rng(7)
    world, meshes = World(), MeshList([cube_mesh(), torus_mesh()])
    materials(world)
    world.spawn_batch(
        n,
        Transform(
            position=rng.uniform(-50, 50, (n, 3)),
            rotation=rng.normal(size=(n, 4)),
            scale=rng.uniform(0.4, 1.0, (n, 1)).repeat(3, axis=1),
        ),
        Velocity(linear=rng.normal(scale=0.5, size=(n, 3))),
        AngularVelocity(angular=rng.normal(size=(n, 3))),
        Mesh(handle=(rng.random(n) < 0.001).astype(np.uint32), material=rng.integers(0, 6, n, dtype=np.uint32)),
    )
    return world, meshes


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--counts", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    counts = [1_000, 5_000] if args.quick else args.counts
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "bench.scene"
        for n in counts:
            world, meshes = scene(n)
            saves, loads = [], []
            with progress.step(f"{n:,} entities"):
                for _ in range(3):
                    t0 = time.perf_counter()
                    save_world(world, path, resources=scene_codecs(meshes))
                    t1 = time.perf_counter()
                    loaded, _ = load_world(path, World(), resources=scene_codecs(MeshList()))
                    t2 = time.perf_counter()
                    saves.append(t1 - t0)
                    loads.append(t2 - t1)
                    assert len(loaded) == n
                    del loaded  # freed before the next save, as a session replacing its world would
            rows.append(
                {
                    "entities": n,
                    "save_s": round(statistics.median(saves), 4),
                    "load_s": round(statistics.median(loads), 4),
                    "save_best_s": round(min(saves), 4),
                    "load_best_s": round(min(loads), 4),
                    "file_mb": round(path.stat().st_size / 1e6, 2),
                }
            )
    print("entities    save s   load s   (best)           file MB")
    for r in rows:
        best = f"({r['save_best_s']:.3f}, {r['load_best_s']:.3f})"
        print(f"{r['entities']:>9,}  {r['save_s']:7.3f}  {r['load_s']:7.3f}  {best:16} {r['file_mb']:8.1f}")
    return {"benchmark": "scene-io", "machine": machine, "quick": bool(args.quick), "target_s": TARGET_S, "rows": rows}
