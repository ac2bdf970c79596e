"""Render-job scaling: the scaling scene at several entity counts, by threads, mode and recorder,
headless. Per configuration: CPU record ms (the chunk jobs), systems ms (the schedule: motion,
transforms, camera, lights), CPU frame ms (systems + render, minus waits for the GPU), GPU frame ms
(timestamps), FPS (wall clock), draws, visible entities.

One device, scene and world per entity count; renderers per (mode, recorder) share one compiled
native recorder. The Python recorder runs only up to PYTHON_MAX entities (it needs ~10 us a
draw), in chunks of PYTHON_CHUNK_ROWS.
The indirect mode records no draws on the CPU (compute shaders write them): its rows say
recorder "gpu", its record_ms is the jobs writing every row, and its draws and visible counts
come back from the GPU a frame or two late (steady scene: the same numbers).

JSON (schema_version 1): {"benchmark": "scaling", "quick", "machine", "device", "config",
"results": [{"entities", "threads", "mode", "recorder", "frames", "record_ms", "systems_ms", "cpu_ms", "gpu_ms",
"fps", "draws", "visible", "ns_per_draw_record"}], "driver_floor": {...} (bench/driver_floor.py),
"targets": [{"name", "target", "measured", "unit", "op", "met"}]}; a plot `scaling-<slug>.png`
beside it.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine.jobs import JobPool, default_threads

from . import headless_gpu

THREADS = default_threads()
PYTHON_MAX = 10_000
# Up to SMALL_MAX entities a configuration runs SMALL_FRAMES timed frames (a 100-entity frame
# takes ~0.2 ms, and 12 frames gave medians that moved by 2x between runs).
SMALL_MAX = 10_000
SMALL_FRAMES = 300
SMALL_WARMUP = 30
# The Python recorder's rows use small chunks, so that even 10k entities make several jobs and
# the table shows what threads do for it (by default 10k rows would make one job).
PYTHON_CHUNK_ROWS = 2_048


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--entities", type=int, nargs="*", help="entity counts (default: 1 .. 1,000,000)")


def sweep(
    entities: int, thread_counts: list[int], frames: int, warmup: int, size: tuple[int, int]
) -> list[dict[str, Any]]:
    from ecs_engine.app.report import describe_device
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.ecs.world import World
    from ecs_engine.gpu.native_recorder import NativeRecorder
    from ecs_engine.render.frame.renderer import Renderer

    rows = []
    with headless_gpu(*size) as (device, target, meshes):
        native = NativeRecorder(device)
        world = World()
        scene_builder("scaling", entities)(world, meshes.add)
        schedule = default_schedule()
        start = snapshot(world)
        configs = [(m, "native") for m in ("per_entity", "instanced")] + [("indirect", "gpu")]
        if entities <= PYTHON_MAX:
            configs += [(m, "python") for m in ("per_entity", "instanced")]
        for mode, recorder in configs:
            if mode == "indirect" and not device.features.get("drawIndirectCount"):
                continue
            renderer = Renderer(
                device,
                target,
                meshes,
                mode=mode,
                recorder="native" if recorder == "gpu" else recorder,
                native_recorder=native,
                **({"chunk_rows": PYTHON_CHUNK_ROWS} if recorder == "python" else {}),
            )
            try:
                for threads in thread_counts:
                    restore(world, start)  # every configuration starts from the same scene
                    with JobPool(threads) as pool:
                        world.resources[JobPool] = renderer.jobs = pool
                        rows.append(
                            measure(world, schedule, renderer, frames, warmup)
                            | {
                                "entities": entities,
                                "threads": threads,
                                "mode": mode,
                                "recorder": recorder,
                                "device": describe_device(device),
                            }
                        )
            finally:
                renderer.destroy()
    return rows


def snapshot(world: Any) -> list[np.ndarray]:
    """What the scene's systems move (transforms, orbit phases), to put back between runs: 330
    frames of motion carry entities out of view and would make later configurations cheaper."""
    from ecs_engine.components import Orbit, Transform

    saved = []
    for batch in world.query(Transform, write=()):
        saved += [batch[Transform].position.copy(), batch[Transform].rotation.copy()]
    for batch in world.query(Orbit, write=()):
        saved.append(batch[Orbit].phase.copy())
    return saved


def restore(world: Any, saved: list[np.ndarray]) -> None:
    from ecs_engine.components import Orbit, Transform

    values = iter(saved)
    for batch in world.query(Transform):
        batch[Transform].position[...] = next(values)
        batch[Transform].rotation[...] = next(values)
    for batch in world.query(Orbit):
        batch[Orbit].phase[...] = next(values)


def measure(
    world: Any, schedule: Any, renderer: Any, frames: int, warmup: int, dt: float | None = None
) -> dict[str, Any]:
    """Medians over `frames` after `warmup`; `dt` goes to the renderer (temporal culling needs it)."""
    record, systems, cpu, gpu, ends = [], [], [], [], []
    for i in range(warmup + frames):
        t0 = time.perf_counter()
        schedule.run(world, 1 / 60)
        t1 = time.perf_counter()
        stats = renderer.render(world, dt=dt)
        now = time.perf_counter()
        if i >= warmup:
            record.append(stats.record_ms)
            systems.append((t1 - t0) * 1e3)
            cpu.append((now - t0) * 1e3 - stats.wait_ms)
            ends.append(now)
            if stats.gpu_ms is not None:
                gpu.append(stats.gpu_ms)
    renderer.device.wait_idle()
    wall = ends[-1] - ends[0]
    rec = float(np.median(record))
    return {
        "frames": frames,
        "record_ms": rec,
        "systems_ms": float(np.median(systems)),
        "cpu_ms": float(np.median(cpu)),
        "gpu_ms": float(np.median(gpu)) if gpu else None,
        "fps": (len(ends) - 1) / wall if wall > 0 else 0.0,
        "draws": stats.draws,
        "visible": stats.instances,
        "ns_per_draw_record": None if renderer.mode == "indirect" else rec * 1e6 / max(stats.draws - 1, 1),
    }


def targets(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    by = {(r["entities"], r["threads"], r["mode"], r["recorder"]): r for r in results}
    n = max(r["entities"] for r in results)
    tmax = max(r["threads"] for r in results)

    def add(name: str, target: float, measured: float | None, unit: str, op: str) -> None:
        if measured is None:
            return
        met = measured <= target if op == "<=" else measured >= target
        out.append({"name": name, "target": target, "measured": measured, "unit": unit, "op": op, "met": bool(met)})

    small = by.get((100, 1, "instanced", "native"))
    add(
        "instanced: CPU frame ms, 100 entities (cubes and lights), 1 thread",
        0.25,
        small["cpu_ms"] if small else None,
        "ms",
        "<=",
    )
    one = by.get((n, 1, "per_entity", "native"))
    top = by.get((n, tmax, "per_entity", "native"))
    add(
        f"per_entity native: record ns per draw, 1 thread, {n:,} entities",
        50.0,
        one["ns_per_draw_record"] if one else None,
        "ns",
        "<=",
    )
    add(
        f"per_entity native: record speed-up {tmax} threads vs 1, {n:,} entities",
        6.0,
        one["record_ms"] / top["record_ms"] if one and top and tmax > 1 else None,
        "x",
        ">=",
    )
    inst = by.get((n, tmax, "instanced", "native"))
    add(
        f"instanced: CPU frame ms, {n:,} moving entities, {tmax} threads",
        8.0,
        inst["cpu_ms"] if inst else None,
        "ms",
        "<=",
    )
    indirect = by.get((n, tmax, "indirect", "gpu"))
    add(
        f"indirect (same bar as instanced): CPU frame ms, {n:,} moving entities, {tmax} threads",
        8.0,
        indirect["cpu_ms"] if indirect else None,
        "ms",
        "<=",
    )
    return out


def plot(results: list[dict[str, Any]], path: Path) -> None:
    from . import pyplot, save_figure

    plt = pyplot()

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for ax, mode in zip(axes, ("per_entity", "instanced", "indirect")):
        for n, rec in sorted({(r["entities"], r["recorder"]) for r in results if r["mode"] == mode}):
            rows = sorted(
                (r for r in results if r["mode"] == mode and r["entities"] == n and r["recorder"] == rec),
                key=lambda r: r["threads"],
            )
            if n >= 1000 or n == max(r["entities"] for r in results):
                ax.plot(
                    [r["threads"] for r in rows],
                    [r["record_ms"] for r in rows],
                    marker="o",
                    linestyle="--" if rec == "python" else "-",
                    label=f"{n:,} {rec}",
                )
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("threads")
        ax.set_ylabel("record ms per frame (median)" if mode != "indirect" else "row-writing jobs ms (median)")
        ax.set_title(mode)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    save_figure(fig, path)


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    if args.quick:
        counts, frames, warmup, size = [100, 2_000], 4, 2, (160, 120)
        thread_counts = sorted({1, min(2, THREADS)})
    else:
        counts, frames, warmup, size = [1, 100, 1_000, 10_000, 100_000, 1_000_000], 12, 4, (640, 360)
        thread_counts = [t for t in (1, 2, 4, 8, 16) if t <= THREADS]
    counts = args.entities or counts
    results: list[dict[str, Any]] = []
    progress.total = len(counts) + 1
    for n in counts:
        # small scenes take well under a millisecond a frame: more frames steady their medians
        n_frames, n_warmup = (SMALL_FRAMES, SMALL_WARMUP) if n <= SMALL_MAX and not args.quick else (frames, warmup)
        with progress.step(f"{n:,} entities: threads {thread_counts}, every mode and recorder"):
            results.extend(sweep(n, thread_counts, n_frames, n_warmup, size))
    floor_draws = 20_000 if args.quick else 1_000_000
    with progress.step(f"driver floor: {floor_draws:,} bare push + draw calls, 1 thread"):
        floor = measure_driver_floor(floor_draws, size)
    doc = {
        "benchmark": "scaling",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": results[0]["device"] if results else None,
        "config": {
            "entities": counts,
            "threads": thread_counts,
            "frames": frames,
            "warmup": warmup,
            "small_max": SMALL_MAX,
            "small_frames": SMALL_FRAMES,
            "small_warmup": SMALL_WARMUP,
            "size": list(size),
            "python_max": PYTHON_MAX,
            "python_chunk_rows": PYTHON_CHUNK_ROWS,
        },
        "results": results,
        "driver_floor": floor,
        "targets": targets(results),
    }
    out = Path(args.out) / f"scaling-{machine['slug']}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    plot(results, out)
    print(
        f"{'entities':>9} {'mode':10} {'rec':6} {'thr':>3} {'record ms':>10} {'sys ms':>7} {'cpu ms':>8} {'gpu ms':>8} "
        f"{'fps':>7} {'draws':>8} {'ns/draw':>8}"
    )
    for r in results:
        gpu = f"{r['gpu_ms']:.2f}" if r["gpu_ms"] is not None else "n/a"
        print(
            f"{r['entities']:9,} {r['mode']:10} {r['recorder']:6} {r['threads']:3} {r['record_ms']:10.2f} "
            f"{r['systems_ms']:7.2f} "
            f"{r['cpu_ms']:8.2f} {gpu:>8} {r['fps']:7.1f} {r['draws']:8} "
            f"{'-' if r['ns_per_draw_record'] is None else format(r['ns_per_draw_record'], '8.0f'):>8}"
        )
    print(
        f"driver floor, 1 thread, {floor['draws']:,} calls in secondaries of {floor['per_buffer']:,}: "
        f"push + draw {floor['push_draw_ns']:.0f} ns, draw alone {floor['draw_ns']:.0f} ns, "
        f"push alone {floor['push_ns']:.0f} ns"
    )
    for t in doc["targets"]:
        print(
            f"target {'MET ' if t['met'] else 'MISS'} {t['name']}: {t['measured']:.3g} {t['unit']} "
            f"(target {t['op']} {t['target']})"
        )
    return doc


def measure_driver_floor(draws: int, size: tuple[int, int]) -> dict[str, Any]:
    """See bench/driver_floor.py: what the driver alone costs per per_entity draw."""
    from ecs_engine.render.assets.primitives import cube_mesh

    from .driver_floor import measure as floor

    with headless_gpu(*size) as (device, target, meshes):
        meshes.add(cube_mesh())
        return floor(device, target, meshes, draws)
