"""The hierarchy: HierarchySystem over R roots with 10 children each (half of them under another
child, so two levels below the roots), 1k to 100k roots (11k to 1.1M entities with Parent).

Measured per size and thread count (the world's JobPool: each level's rows are cut into chunks
on it), median of the frames: `still`, a hierarchy whose parents move every frame
(the roots' Transforms written) but whose structure stays, so the system keeps its plan; and
`replanned`, the same frame with the plan made again (what a frame that spawns or reparents in
those tables costs). The world matrices are checked against a NumPy reference on a sample.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np

from ecs_engine import World, native
from ecs_engine.components import Mesh, Parent, Transform, WorldMatrix
from ecs_engine.jobs import JobPool, default_threads
from ecs_engine.maths.decompose import trs_matrices
from ecs_engine.systems import HierarchySystem

CHILDREN = 10
THREADS = default_threads()


def make_world(roots: int) -> tuple[World, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    world = World()
    top = world.spawn_batch(roots, Transform(position=rng.uniform(-100, 100, (roots, 3))), Mesh())
    half = roots * CHILDREN // 2
    first = world.spawn_batch(
        half,
        Transform(position=rng.normal(size=(half, 3)), rotation=rng.normal(size=(half, 4))),
        Parent(entity=np.repeat(top, CHILDREN // 2)),
        Mesh(),
    )
    second = world.spawn_batch(half, Transform(position=(0.0, 1.0, 0.0)), Parent(entity=first), Mesh())
    return world, top, first, second


def check(world: World, top: np.ndarray, first: np.ndarray, second: np.ndarray) -> None:
    for k in np.linspace(0, len(second) - 1, 16).astype(int):
        chain = [top[k // (CHILDREN // 2)], first[k], second[k]]
        want = np.eye(4)
        for e in chain:
            t = world.get(e, Transform)
            want = want @ trs_matrices(t.position[None], t.rotation[None], t.scale[None])[0]
        got = world.get(second[k], WorldMatrix).matrix
        if not np.allclose(got, want, atol=1e-9):
            raise AssertionError(f"world matrix of entity {second[k]} is wrong")


def frame_ms(roots: int, frames: int, replan: bool, threads: int) -> float:
    world, top, first, second = make_world(roots)
    with JobPool(threads) as pool:
        world.resources[JobPool] = pool
        return _timed(world, top, first, second, frames, replan)


def _timed(world: World, top: np.ndarray, first: np.ndarray, second: np.ndarray, frames: int, replan: bool) -> float:
    system = HierarchySystem()
    rng = np.random.default_rng(4)
    world.run_system(system, 0.0)  # compile and plan
    times = []
    for _ in range(frames):
        world.set(top, Transform, position=rng.uniform(-100, 100, (len(top), 3)))
        if replan:
            system._plan = None
        t0 = time.perf_counter()
        world.run_system(system, 0.0)
        times.append((time.perf_counter() - t0) * 1e3)
    check(world, top, first, second)
    return statistics.median(times)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--frames", type=int, default=20, help="frames timed per size")


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    sizes = (100, 1_000) if args.quick else (1_000, 10_000, 100_000)
    frames = 3 if args.quick else args.frames
    rows = []
    for roots in sizes:
        for threads in sorted({1, THREADS}):
            with progress.step(f"{roots:,} roots, {roots * CHILDREN:,} with Parent, {threads} threads"):
                still = frame_ms(roots, frames, False, threads)
                replanned = frame_ms(roots, frames, True, threads)
            row = {"roots": roots, "with_parent": roots * CHILDREN, "threads": threads}
            rows.append(row | {"still_ms": round(still, 3), "replanned_ms": round(replanned, 3)})
    print(f"HierarchySystem, {CHILDREN} children a root over two levels (median of {frames} frames):")
    print("    roots  with Parent  threads   still ms  replanned ms")
    for r in rows:
        sizes_text = f"{r['roots']:>9,}  {r['with_parent']:>11,}  {r['threads']:7}"
        print(f"{sizes_text}  {r['still_ms']:9.2f}  {r['replanned_ms']:12.2f}")
    doc = {"benchmark": "hierarchy", "machine": machine, "quick": bool(args.quick), "numba": native.AVAILABLE}
    return doc | {"frames": frames, "rows": rows}
