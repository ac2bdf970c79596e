"""Culling methods on the GPU host: the scaling scene (every entity moving and spinning) headless
at 1280x720, at 10k, 100k and 1M entities, with all threads, for each culling method a mode
offers: the CPU-culled instanced mode with frustum, temporal and no culling, the indirect mode
with frustum, occlusion (two-phase, render/culling/occlusion_passes.py) and no culling. Per configuration: CPU
frame ms (systems + render, minus waits), GPU ms (timestamps), wall ms per frame (the loop runs
flat out, frames in flight: the slower of the two), rows drawn. The target: the 1M scene at 120
FPS or more (wall), occlusion culling.

JSON (schema_version 1): {"benchmark": "culling-methods", "quick", "machine", "config",
"results": [{"entities", "mode", "culling", "threads", "frames", "cpu_ms", "gpu_ms", "wall_ms",
"fps", "visible", "draws", "record_ms", "systems_ms"}], "targets": [...]}.
"""

from __future__ import annotations

import argparse
from typing import Any

from ecs_engine.jobs import JobPool, default_threads

from . import headless_gpu
from .scaling import measure, restore, snapshot

METHODS = (
    ("instanced", "frustum"),
    ("instanced", "temporal"),
    ("instanced", "none"),
    ("indirect", "frustum"),
    ("indirect", "occlusion"),
    ("indirect", "none"),
)
TARGET_FPS = 120.0
TARGET_METHOD = ("indirect", "occlusion")  # (mode, culling) of METHODS the FPS target is for


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--entities", type=int, nargs="*", help="entity counts (default: 10k, 100k, 1M)")
    parser.add_argument("--size", type=int, nargs=2, metavar=("W", "H"), help="target size (default 1280 720)")
    parser.add_argument("--frames", type=int, help="timed frames per configuration (default 60)")
    names = [f"{m}:{c}" for m, c in METHODS]
    parser.add_argument(
        "--methods", nargs="*", choices=names, metavar="MODE:CULLING", help=f"default: all of {', '.join(names)}"
    )


def methods(names: list[str] | None) -> list[tuple[str, str]]:
    """The (mode, culling) pairs asked for (argparse checked the names), or every one."""
    if not names:
        return list(METHODS)
    return [(mode, culling) for mode, _, culling in (name.partition(":") for name in names)]


def sweep(
    entities: int, configs: list[tuple[str, str]], threads: int, frames: int, size: tuple[int, int]
) -> list[dict[str, Any]]:
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.ecs.world import World
    from ecs_engine.render.frame.renderer import Renderer

    rows = []
    with headless_gpu(*size) as (device, target, meshes), JobPool(threads) as pool:
        world = World()
        scene_builder("scaling", entities)(world, meshes.add)
        world.resources[JobPool] = pool
        schedule = default_schedule()
        start = snapshot(world)
        for mode, culling in configs:
            if mode == "indirect" and not device.features.get("drawIndirectCount"):
                continue
            renderer = Renderer(device, target, meshes, mode=mode, culling=culling, jobs=pool)
            try:
                restore(world, start)  # every configuration starts from the same scene
                m = measure(world, schedule, renderer, frames, max(10, frames // 5), dt=1 / 60)
            finally:
                renderer.destroy()
            rows.append(
                {"entities": entities, "mode": mode, "culling": culling, "threads": threads}
                | m
                | {"wall_ms": 1e3 / m["fps"] if m["fps"] else None}
            )
    return rows


def targets(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    big = [r for r in results if (r["mode"], r["culling"]) == TARGET_METHOD and r["entities"] >= 1_000_000]
    if not big:
        return []
    r = max(big, key=lambda r: r["entities"])
    return [
        {
            "name": f"{r['entities']:,} moving entities, indirect + occlusion, wall FPS",
            "target": TARGET_FPS,
            "measured": r["fps"],
            "unit": "FPS",
            "op": ">=",
            "met": r["fps"] >= TARGET_FPS,
        }
    ]


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    threads = default_threads()
    if args.quick:
        counts, frames, size = [500], 4, (160, 120)
    else:
        counts, frames, size = [10_000, 100_000, 1_000_000], 60, (1280, 720)
    counts = args.entities or counts
    frames = args.frames or frames
    size = tuple(args.size) if args.size else size
    configs = methods(args.methods)
    results: list[dict[str, Any]] = []
    progress.total = len(counts)
    for n in counts:
        with progress.step(f"{n:,} entities at {size[0]}x{size[1]}, {threads} threads: {len(configs)} methods"):
            results.extend(sweep(n, configs, threads, frames, size))
    print(
        f"{'entities':>9} {'mode':10} {'culling':10} {'cpu ms':>8} {'gpu ms':>8} {'wall ms':>8} {'fps':>7} {'drawn':>9}"
    )
    for r in results:
        gpu = f"{r['gpu_ms']:.2f}" if r["gpu_ms"] is not None else "n/a"
        print(
            f"{r['entities']:9,} {r['mode']:10} {r['culling']:10} {r['cpu_ms']:8.2f} {gpu:>8} "
            f"{r['wall_ms']:8.2f} {r['fps']:7.1f} {r['visible']:9,}"
        )
    doc = {
        "benchmark": "culling-methods",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "config": {"entities": counts, "frames": frames, "size": list(size), "threads": threads},
        "results": results,
        "targets": targets(results),
    }
    for t in doc["targets"]:
        print(
            f"target {'MET ' if t['met'] else 'MISS'} {t['name']}: {t['measured']:.1f} (target {t['op']} {t['target']})"
        )
    return doc
