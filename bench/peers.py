"""The scaling workload in this engine and in pygfx, side by side (issue 17): N moving, spinning
cubes (0.1% torus knots), 6 orbiting point lights, 640x360, the GPU synced every frame; wall ms
per frame at 1k, 10k, 100k and 1M entities.

Variants (`--variants`, default all four):
- engine-instanced, engine-indirect: demos/scaling.py's scene headless, the stock schedule and
  Renderer in that mode (indirect only where the device has drawIndirectCount), a JobPool of
  every core this process may use. A frame is `schedule.run` then `renderer.render(world,
  readback=True)`: the frame is copied to the target's host-visible buffer and its fence waited
  for, so the GPU has finished it when render returns.
- pygfx-instanced, pygfx-objects: the same scene's numbers in pygfx (bench/peers_pygfx.py says
  how: one InstancedMesh per mesh, or one Mesh per entity, moved in NumPy, read back each frame).
  One object per entity is slow: it runs only up to `--objects-max` entities (more are recorded
  as skipped), and a pygfx configuration whose frames (warm-up included) pass `--budget`
  seconds stops timing early (after 3 timed frames at least; its row says so).

Wall ms is the median over the timed frames after the warm-up, from the start of the frame's
motion to the frame read back. The ratios divide each other variant's by engine-instanced's at
the same N. pygfx needs the optional extra: `pip install -e .[peers]`.

JSON (schema_version 1): {"benchmark": "peers", "quick", "machine", "device" (the engine's
Vulkan device), "peer": {"versions", "adapter", "renderer", "notes"} (null without a pygfx
variant), "config": {"entities", "variants", "frames", "warmup", "size", "threads", "objects_max",
"budget_s"}, "results": [{"entities", "variant", "wall_ms", "frames", ... | "skipped": why}],
"ratios": [{"entities", "engine_instanced_ms", "<variant>_x", ...}], "plot": "peers-<slug>.png" or null
(without matplotlib)}; the plot is wall ms against entities, one line per variant.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine.errors import UsageError
from ecs_engine.jobs import JobPool, default_threads

from . import headless_gpu
from . import peers_pygfx as peer

THREADS = default_threads()
ENGINE_VARIANTS = ("engine-instanced", "engine-indirect")
PYGFX_VARIANTS = ("pygfx-instanced", "pygfx-objects")
VARIANTS = ENGINE_VARIANTS + PYGFX_VARIANTS
COUNTS = (1_000, 10_000, 100_000, 1_000_000)
QUICK_COUNTS = (100, 1_000)
OBJECTS_MAX = 10_000
INSTALL = "pip install -e .[peers]"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--entities", type=int, nargs="+", help="entity counts (default: 1k, 10k, 100k, 1M)")
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS), help="what to measure")
    parser.add_argument("--frames", type=int, default=None, help="timed frames per configuration (default 60)")
    parser.add_argument("--warmup", type=int, default=None, help="frames before timing (default 10)")
    parser.add_argument(
        "--objects-max",
        type=int,
        default=OBJECTS_MAX,
        help=f"pygfx-objects runs up to this many entities (default {OBJECTS_MAX:,})",
    )
    parser.add_argument(
        "--budget",
        type=float,
        default=30.0,
        help="seconds of frames, warm-up included, per pygfx configuration (default 30)",
    )


def preflight(args: argparse.Namespace) -> None:
    """Before anything runs: sizes that make sense; pygfx installed and a GPU adapter for it, when a
    pygfx variant is asked for."""
    if args.entities is not None and min(args.entities) < 1:
        raise UsageError("--entities: every count must be at least 1")
    if (args.frames is not None and args.frames < 1) or (args.warmup is not None and args.warmup < 0):
        raise UsageError("--frames must be at least 1 and --warmup at least 0")
    if args.objects_max < 0 or args.budget < 0:
        raise UsageError("--objects-max and --budget must not be negative")
    if not any(v in PYGFX_VARIANTS for v in args.variants):
        return
    missing = peer.check_available()
    if missing is not None:
        raise UsageError(
            f"the pygfx variants need the optional 'peers' extra ({missing} is not installed): run `{INSTALL}` "
            f"in the checkout, or measure the engine alone with --variants {' '.join(ENGINE_VARIANTS)}"
        )
    try:
        peer.adapter_info()
    except RuntimeError as exc:
        raise UsageError(f"pygfx cannot draw here: {exc}") from None


def engine_rows(n: int, variants: list[str], frames: int, warmup: int) -> tuple[list[dict[str, Any]], Any]:
    """The engine variants at n entities, on a device of their own; and that device's description."""
    from ecs_engine.app.report import describe_device
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.ecs.world import World
    from ecs_engine.gpu.native_recorder import NativeRecorder
    from ecs_engine.render.frame.renderer import Renderer

    from .scaling import restore, snapshot

    rows = []
    with headless_gpu(peer.WIDTH, peer.HEIGHT) as (device, target, meshes):
        native, world = NativeRecorder(device), World()
        scene_builder("scaling", n)(world, meshes.add)
        schedule, start = default_schedule(), snapshot(world)
        for variant in variants:
            mode = variant.removeprefix("engine-")
            if mode == "indirect" and not device.features.get("drawIndirectCount"):
                rows.append({"entities": n, "variant": variant, "skipped": "the device lacks drawIndirectCount"})
                continue
            renderer = Renderer(device, target, meshes, mode=mode, recorder="native", native_recorder=native)
            try:
                restore(world, start)  # each variant starts from the same scene
                with JobPool(THREADS) as pool:
                    world.resources[JobPool] = renderer.jobs = pool
                    timed = engine_frames(world, schedule, renderer, frames, warmup)
                rows.append({"entities": n, "variant": variant} | timed)
            finally:
                renderer.destroy()
        return rows, describe_device(device)


def engine_frames(world: Any, schedule: Any, renderer: Any, frames: int, warmup: int) -> dict[str, Any]:
    wall, systems, gpu = [], [], []
    for i in range(warmup + frames):
        t0 = time.perf_counter()
        schedule.run(world, peer.DT)
        t1 = time.perf_counter()
        stats = renderer.render(world, readback=True)  # waits for the frame's fence
        t2 = time.perf_counter()
        if i >= warmup:
            wall.append((t2 - t0) * 1e3)
            systems.append((t1 - t0) * 1e3)
            if stats.gpu_ms is not None:
                gpu.append(stats.gpu_ms)
    renderer.device.wait_idle()
    return {
        "wall_ms": float(np.median(wall)),
        "update_ms": float(np.median(systems)),  # the schedule: motion, orbits, matrices
        "render_ms": float(np.median(np.subtract(wall, systems))),
        "gpu_ms": float(np.median(gpu)) if gpu else None,
        "frames": len(wall),
        "draws": stats.draws,
        "visible": stats.instances,
    }


def pygfx_rows(
    canvas: Any, n: int, variants: list[str], frames: int, warmup: int, objects_max: int, budget: float
) -> list[dict[str, Any]]:
    numbers = peer.scene_numbers(n)
    rows = []
    for variant in variants:
        if variant == "pygfx-objects" and n > objects_max:
            why = f"too slow: one object per entity runs up to --objects-max {objects_max:,}"
            rows.append({"entities": n, "variant": variant, "skipped": why})
            continue
        kind = variant.removeprefix("pygfx-")
        rows.append({"entities": n, "variant": variant} | peer.measure(canvas, numbers, kind, frames, warmup, budget))
    return rows


def ratios(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each variant's wall ms over engine-instanced's at the same N (None where either is missing)."""
    by = {(r["entities"], r["variant"]): r.get("wall_ms") for r in results}
    out = []
    for n in dict.fromkeys(r["entities"] for r in results):
        base = by.get((n, "engine-instanced"))
        entry: dict[str, Any] = {"entities": n, "engine_instanced_ms": base}
        for variant in VARIANTS[1:]:
            ms = by.get((n, variant))
            entry[f"{variant.replace('-', '_')}_x"] = ms / base if ms is not None and base else None
        out.append(entry)
    return out


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    preflight(args)  # bench.__main__ calls it first; a direct caller gets the same refusal
    counts = args.entities or (QUICK_COUNTS if args.quick else COUNTS)
    frames = args.frames if args.frames is not None else (5 if args.quick else 60)
    warmup = args.warmup if args.warmup is not None else (2 if args.quick else 10)
    engine = [v for v in VARIANTS if v in args.variants and v in ENGINE_VARIANTS]
    pygfx = [v for v in VARIANTS if v in args.variants and v in PYGFX_VARIANTS]
    results: list[dict[str, Any]] = []
    device = None
    canvas = peer.Canvas() if pygfx else None
    progress.total = len(counts) * (bool(engine) + bool(pygfx))
    try:
        for n in counts:
            if engine:
                with progress.step(f"{n:,} entities: this engine, {', '.join(engine)}"):
                    rows, device = engine_rows(n, engine, frames, warmup)
                    results += rows
            if canvas is not None:
                with progress.step(f"{n:,} entities: pygfx, {', '.join(pygfx)}"):
                    results += pygfx_rows(canvas, n, pygfx, frames, warmup, args.objects_max, args.budget)
    finally:
        if canvas is not None:
            canvas.close()
    doc = {
        "benchmark": "peers",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": device,
        "peer": peer_entry() if pygfx else None,
        "config": {
            "entities": list(counts),
            "variants": engine + pygfx,
            "frames": frames,
            "warmup": warmup,
            "size": [peer.WIDTH, peer.HEIGHT],
            "threads": THREADS,
            "objects_max": args.objects_max,
            "budget_s": args.budget,
        },
        "results": results,
        "ratios": ratios(results),
    }
    print(format_table(doc))
    out = Path(args.out) / f"peers-{machine['slug']}.png"
    try:
        plot(doc, out)
        doc["plot"] = out.name
    except ImportError:  # matplotlib comes with the bench and dev extras
        progress.note("matplotlib is missing: no plot")
        doc["plot"] = None
    return doc


def peer_entry() -> dict[str, Any]:
    return {
        "versions": peer.versions(),
        "adapter": peer.adapter_info(),
        "renderer": dict(peer.RENDERER, side="front", canvas="rendercanvas OffscreenRenderCanvas"),
        "notes": [
            "the same seed's numbers as the engine's scaling scene (read out of its World), knots included",
            "sync: OffscreenRenderCanvas.draw() reads the frame back (a mapped buffer, waited for) every frame",
            "motion in NumPy with the engine's reference kernels (integrate_linear_numpy, integrate_angular_numpy)",
            "instanced: one InstancedMesh per mesh (cube, knot), one Phong material (pygfx has no per-instance one)",
            "objects: one Mesh per entity, the palette's six Phong materials, position and rotation set each frame",
        ],
    }


def format_table(doc: dict[str, Any]) -> str:
    by = {(r["entities"], r["variant"]): r for r in doc["results"]}
    variants = doc["config"]["variants"]
    lines = [
        f"wall ms per frame (median), {doc['config']['size'][0]}x{doc['config']['size'][1]}, GPU synced each frame; "
        f"x: over engine-instanced",
        f"{'entities':>9} " + " ".join(f"{v:>17}" for v in variants),
    ]
    ratio = {r["entities"]: r for r in doc["ratios"]}
    for n in doc["config"]["entities"]:
        cells = []
        for v in variants:
            r = by.get((n, v), {})
            if "wall_ms" not in r:
                cells.append("skipped")
                continue
            x = ratio[n].get(f"{v.replace('-', '_')}_x")
            early = "*" if r.get("stopped_early") else ""
            cells.append(f"{r['wall_ms']:.2f}{early}" + (f" ({x:.1f}x)" if x is not None else ""))
        lines.append(f"{n:>9,} " + " ".join(f"{c:>17}" for c in cells))
    skipped = {r["skipped"] for r in doc["results"] if "skipped" in r}
    lines += [f"skipped: {why}" for why in sorted(skipped)]
    if any(r.get("stopped_early") for r in doc["results"]):
        lines.append(f"*: stopped after --budget {doc['config']['budget_s']:g} s, fewer frames timed")
    return "\n".join(lines)


def plot(doc: dict[str, Any], path: Path) -> None:
    from . import pyplot, save_figure

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.4))
    for variant in doc["config"]["variants"]:
        points = [(r["entities"], r["wall_ms"]) for r in doc["results"] if r["variant"] == variant and "wall_ms" in r]
        if points:
            ax.plot(
                *zip(*sorted(points)), marker="o", linestyle="--" if variant.startswith("pygfx") else "-", label=variant
            )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("entities")
    ax.set_ylabel("wall ms per frame (median), GPU synced")
    ax.set_title(f"scaling workload at {doc['config']['size'][0]}x{doc['config']['size'][1]}: this engine and pygfx")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path)
