"""A crowd of independently animated skinned characters: demos/character.py's humanoid (24 joints,
1,728 vertices) spawned N times from its .glb, each playing idle, walk or run at its own phase
and speed, headless at 1920x1080, with the sun casting no shadow and then casting one.

Per crowd size (1k and 10k) and shadows off/on, and as a control the same mesh drawn N times
still (no skin, no clips: what its triangles cost the GPU without skinning), run twice in
alternating order (each keeps the smaller of its two medians, as bench/lights.py does): the
CPU frame (systems and render, minus waits for the GPU), the GPU frame (timestamps), and each
system's CPU time (animation: clip sampling; hierarchy: the joints' world matrices; skins: the
joint matrices and pose bounds). Derived: CPU microseconds per joint (the three systems over
N x 24 joints) and GPU nanoseconds per vertex drawn (N x 1,728, camera pass). The target (the
issue): 10k characters at 120 FPS end to end without shadows, i.e. max(CPU, GPU) at most 8.33 ms.

JSON (schema_version 1): {"benchmark": "animation", "quick", "machine", "device", "config":
{"width", "height", "warmup", "frames", "counts", "threads", "mode", "joints", "vertices"}, "results":
[{"characters", "shadows", "still", "cpu_ms", "gpu_ms", "systems_ms": {name: ms}, "us_per_joint",
"ns_per_vertex", "runs" (each with "python_loop_ns": the core's speed before and after it,
machine.py)}], "target": {"characters", "frame_ms", "limit_ms", "met"}}.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine.jobs import default_threads

from . import timed_frames
from .machine import python_loop_ns

COUNTS = (1_000, 10_000)
QUICK_COUNTS = (20,)
WIDTH, HEIGHT = 1920, 1080
TARGET_CHARACTERS, TARGET_MS = 10_000, 1000.0 / 120.0
SPACING = 1.3  # m between characters
SYSTEMS = ("animation", "hierarchy", "skins")
THREADS = min(16, default_threads())


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--counts", type=int, nargs="+", help="crowd sizes (default 1k and 10k)")
    parser.add_argument(
        "--mode", default="instanced", choices=("instanced", "indirect"),
        help="render mode (indirect: GPU culling and levels of detail by projected size)",
    )  # fmt: skip


class _Timer:
    """Each system's run, in ms (the schedule's SystemTimer)."""

    def __init__(self) -> None:
        self.ms: dict[str, list[float]] = {}

    def system(self, name: str, start_ns: int, end_ns: int) -> None:
        self.ms.setdefault(name, []).append((end_ns - start_ns) / 1e6)


def crowd(gpu: Any, n: int, shadows: bool, folder: Path, still: bool = False) -> tuple[Any, Any]:
    """The world (N characters in a square, the camera above them, the sun) and its schedule.
    `still`: the characters' mesh drawn N times without skin or clips (what the triangles cost)."""
    from ecs_engine.animation.player import AnimationSystem
    from ecs_engine.app import plugins
    from ecs_engine.components import Camera, DirectionalLight, Mesh, Shadow, Transform
    from ecs_engine.components.animation import AnimationPlayer
    from ecs_engine.demos.character import CLIPS, character_file
    from ecs_engine.ecs.world import World
    from ecs_engine.maths.camera import look_rotation
    from ecs_engine.render.assets.gltf.scene import load_gltf
    from ecs_engine.render.assets.materials import materials

    meshes = gpu[2]
    world = World()
    scene = load_gltf(character_file(folder), meshes.add, materials(world))
    side = int(np.ceil(np.sqrt(n)))
    k = np.arange(n)
    positions = np.c_[(k % side - side / 2) * SPACING, np.zeros(n), (k // side - side / 2) * SPACING]
    rng = np.random.default_rng(7)
    turns = rng.uniform(0, 2 * np.pi, n)
    rotations = np.c_[np.zeros(n), np.sin(turns / 2), np.zeros(n), np.cos(turns / 2)]
    if still:
        (handle, material), *_ = next(node.parts for node in scene.nodes if node.parts)
        world.spawn_batch(n, Transform(position=positions, rotation=rotations), Mesh(handle=handle, material=material))
    else:
        roots = scene.spawn_many(world, n, positions, rotations)
        handles = scene.clip_handles(world)
        names = list(CLIPS)
        choice = rng.integers(0, len(names), n)
        periods = np.array([CLIPS[name] for name in names])[choice]
        clip = np.array([handles[name] for name in names], np.int32)[choice]
        times, speeds = rng.uniform(0, 1, n) * periods, rng.uniform(0.9, 1.1, n)
        world.set(roots, AnimationPlayer(clip=clip, time=times, speed=speeds))
    extent = side * SPACING
    eye = np.array([0.0, 0.75 * extent + 4.0, 0.75 * extent + 6.0])
    world.spawn(Transform(position=eye, rotation=look_rotation(-eye)), Camera(fov_y=1.0, far=4.0 * extent + 50.0))
    cast = [Shadow(cascades=4, distance=2.0 * extent + 20.0)] if shadows else []
    world.spawn(Transform(rotation=look_rotation((0.4, -1.0, 0.3))), DirectionalLight(illuminance=1.5), *cast)
    schedule = plugins.schedule_of(plugins.SCENE_PLUGINS)  # (MinimalPlugins' AnimationPlugin needs an App)
    schedule.add(AnimationSystem(), "update")
    return world, schedule


def measure(
    gpu: Any, n: int, shadows: bool, still: bool, warmup: int, frames: int, folder: Path, mode: str = "instanced"
) -> dict[str, Any]:
    from ecs_engine.jobs import JobPool
    from ecs_engine.render.frame.renderer import Renderer

    device, target, meshes = gpu
    world, schedule = crowd(gpu, n, shadows, folder, still)
    timer = _Timer()
    schedule.timer = timer
    with JobPool(THREADS) as pool:
        world.resources[JobPool] = pool
        renderer = Renderer(device, target, meshes, jobs=pool, mode=mode)
        try:
            timed = timed_frames(world, schedule, renderer, warmup, frames, warm=timer.ms.clear)
        finally:
            renderer.destroy()
    return {
        **timed,
        "systems_ms": {name: statistics.median(timer.ms.get(name, [0.0])) for name in SYSTEMS},
    }


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    from ecs_engine.demos.character import SKELETON, mesh_arrays

    from . import headless_gpu

    counts = tuple(args.counts) if getattr(args, "counts", None) else (QUICK_COUNTS if args.quick else COUNTS)
    mode = getattr(args, "mode", "instanced")
    warmup, frames = (2, 4) if args.quick else (20, 60)
    joints, vertices = len(SKELETON), len(mesh_arrays()[0])
    configs = [(n, shadows, False) for n in counts for shadows in (False, True)] + [(n, False, True) for n in counts]
    runs: dict[tuple[int, bool, bool], list[dict[str, Any]]] = {}
    progress.total = 2 * len(configs)
    with tempfile.TemporaryDirectory() as folder, headless_gpu(WIDTH, HEIGHT) as gpu:
        for round_ in range(2):
            for n, shadows, still in configs if round_ == 0 else configs[::-1]:
                what = "still meshes" if still else f"shadows {'on' if shadows else 'off'}"
                with progress.step(f"round {round_ + 1}: {n:,} characters, {what}"):
                    before = python_loop_ns()
                    measured = measure(gpu, n, shadows, still, warmup, frames, Path(folder), mode)
                    measured["python_loop_ns"] = [before, python_loop_ns()]
                    runs.setdefault((n, shadows, still), []).append(measured)
        device_info = gpu[0].info.__dict__
    results = []
    for (n, shadows, still), measured in runs.items():
        best = min(measured, key=lambda m: m["cpu_ms"])
        gpu = [m["gpu_ms"] for m in measured if m["gpu_ms"] is not None]
        gpu_ms = min(gpu) if gpu else None
        systems = {name: min(m["systems_ms"][name] for m in measured) for name in SYSTEMS}
        results.append(
            {
                "characters": n,
                "shadows": shadows,
                "still": still,
                "cpu_ms": best["cpu_ms"],
                "gpu_ms": gpu_ms,
                "systems_ms": systems,
                "us_per_joint": 1e3 * sum(systems.values()) / (n * joints),
                "ns_per_vertex": None if gpu_ms is None else 1e6 * gpu_ms / (n * vertices),
                "runs": measured,
            }
        )
    doc = {
        "benchmark": "animation",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": device_info,
        "config": {
            "width": WIDTH,
            "height": HEIGHT,
            "warmup": warmup,
            "frames": frames,
            "counts": list(counts),
            "threads": THREADS,
            "mode": mode,
            "joints": joints,
            "vertices": vertices,
        },
        "results": results,
        "target": target_entry(results),
    }
    print(format_table(doc))
    return doc


def target_entry(results: list[dict[str, Any]]) -> dict[str, Any]:
    found = [r for r in results if r["characters"] == TARGET_CHARACTERS and not r["shadows"] and not r["still"]]
    if not found:
        return {"characters": TARGET_CHARACTERS, "frame_ms": None, "limit_ms": TARGET_MS, "met": None}
    r = found[0]
    frame = max(r["cpu_ms"], r["gpu_ms"] or 0.0)
    return {"characters": TARGET_CHARACTERS, "frame_ms": frame, "limit_ms": TARGET_MS, "met": frame <= TARGET_MS}


def format_table(doc: dict[str, Any]) -> str:
    cfg = doc["config"]
    lines = [
        f"animation at {cfg['width']}x{cfg['height']}, {cfg.get('mode', 'instanced')} mode, {cfg['threads']} threads, "
        f"{cfg['joints']} joints and "
        f"{cfg['vertices']} vertices a character: the smaller of 2 runs' medians",
        f"{'characters':>10} {'shadows':>7} {'CPU ms':>8} {'GPU ms':>8} "
        + " ".join(f"{name + ' ms':>13}" for name in SYSTEMS)
        + f" {'us/joint':>9} {'ns/vertex':>9}",
    ]
    for r in doc["results"]:
        gpu = "-" if r["gpu_ms"] is None else f"{r['gpu_ms']:.2f}"
        per_vertex = "-" if r["ns_per_vertex"] is None else f"{r['ns_per_vertex']:.3f}"
        lines.append(
            f"{r['characters']:>10,} {'still' if r['still'] else 'on' if r['shadows'] else 'off':>7} "
            f"{r['cpu_ms']:>8.2f} {gpu:>8} "
            + " ".join(f"{r['systems_ms'][name]:>13.2f}" for name in SYSTEMS)
            + f" {r['us_per_joint']:>9.3f} {per_vertex:>9}"
        )
    t = doc["target"]
    if t["frame_ms"] is not None:
        lines.append(
            f"target: {t['characters']:,} characters without shadows, frame max(CPU, GPU) {t['frame_ms']:.2f} ms, "
            f"limit {t['limit_ms']:.2f} ms (120 FPS): {'met' if t['met'] else 'NOT met'}"
        )
    return "\n".join(lines)
