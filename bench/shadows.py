"""What shadows cost: the scaling scene (N moving, spinning cubes) with one casting light added,
against the same scene with that light casting nothing, headless at 640x360.

Per entity count (10k, 100k, 1M) and thread count (1 and 16, or all cores when fewer): the
shadowless frame, a directional light with 4 cascades under each filter (hard, PCF, PCSS), a
spot light and a point light (PCF). CPU frame ms (systems + render, minus waits for the GPU) and
GPU ms (timestamps, a frame late); the configurations of one entity count run twice, in
alternating order, and each keeps the smaller of its two runs' medians (bench/lights.py says
why). The target (issue 15): at 100k entities and the most threads, the directional light's
4 cascades cost at most 2x the shadowless CPU frame.

JSON (schema_version 1): {"benchmark": "shadows", "quick", "machine", "device", "config":
{"width", "height", "warmup", "frames", "counts", "threads"}, "results": [{"entities",
"threads", "light", "filter", "cpu_ms", "gpu_ms", "runs": [{"cpu_ms", "gpu_ms"}]}], "target":
{"entities", "threads", "cpu_ms", "baseline_cpu_ms", "ratio", "limit", "met"}}; a plot beside it.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ecs_engine.jobs import default_threads

from . import ratio_verdict, timed_frames

COUNTS = (10_000, 100_000, 1_000_000)
QUICK_COUNTS = (1_000,)
# (light, filter): "none" is the same scene with the light casting nothing
CONFIGS = (
    ("none", "-"),
    ("directional", "hard"),
    ("directional", "pcf"),
    ("directional", "pcss"),
    ("spot", "pcf"),
    ("point", "pcf"),
)
TARGET_ENTITIES, TARGET_RATIO = 100_000, 2.0
WIDTH, HEIGHT = 640, 360


def thread_counts() -> tuple[int, ...]:
    most = min(16, default_threads())
    return (1,) if most == 1 else (1, most)


THREADS = max(thread_counts())  # the most a configuration uses (recorded with the machine)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--counts", type=int, nargs="+", help="entity counts (default 10k, 100k, 1M)")


def add_light(world: Any, light: str, filter_: str) -> None:
    """The configuration's light over the scaling scene's field (centred on the origin)."""
    from ecs_engine.components import DirectionalLight, PointLight, Shadow, SpotLight, Transform
    from ecs_engine.components.shadow import SHADOW_FILTERS
    from ecs_engine.maths.camera import look_rotation

    cast = [] if light == "none" else [Shadow(cascades=4, filter=SHADOW_FILTERS.index(filter_))]
    if light in ("none", "directional"):
        world.spawn(Transform(rotation=look_rotation((0.3, -1.0, 0.2))), DirectionalLight(illuminance=0.5), *cast)
    elif light == "spot":
        world.spawn(
            Transform(position=(0.0, 60.0, 0.0), rotation=look_rotation((0.0, -1.0, 0.01))),
            SpotLight(intensity=4000.0, radius=200.0, outer_angle=1.2, inner_angle=1.0),
            *cast,
        )
    else:
        world.spawn(Transform(position=(0.0, 5.0, 0.0)), PointLight(intensity=400.0, radius=200.0), *cast)


def measure(gpu: Any, n: int, light: str, filter_: str, threads: int, warmup: int, frames: int) -> dict[str, Any]:
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.ecs.world import World
    from ecs_engine.jobs import JobPool
    from ecs_engine.render.frame.renderer import Renderer

    device, target, meshes = gpu
    world = World()
    scene_builder("scaling", n)(world, meshes.add)
    add_light(world, light, filter_)
    schedule = default_schedule()
    with JobPool(threads) as pool:
        world.resources[JobPool] = pool
        renderer = Renderer(device, target, meshes, jobs=pool)
        try:
            return timed_frames(world, schedule, renderer, warmup, frames)
        finally:
            renderer.destroy()


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    from . import headless_gpu

    counts = tuple(args.counts) if getattr(args, "counts", None) else (QUICK_COUNTS if args.quick else COUNTS)
    warmup, frames = (2, 4) if args.quick else (8, 30)
    threads = thread_counts()
    runs: dict[tuple[int, int, str, str], list[dict[str, Any]]] = {}
    progress.total = 2 * len(counts) * len(threads) * len(CONFIGS)
    with headless_gpu(WIDTH, HEIGHT) as gpu:
        for round_ in range(2):
            for n in counts:
                for t in threads:
                    for light, filter_ in CONFIGS if round_ == 0 else CONFIGS[::-1]:
                        with progress.step(f"round {round_ + 1}: {n:,} entities, {t} threads, {light} {filter_}"):
                            runs.setdefault((n, t, light, filter_), []).append(
                                measure(gpu, n, light, filter_, t, warmup, frames)
                            )
        device_info = gpu[0].info.__dict__
    results = [summarise(key, measured) for key, measured in runs.items()]
    doc = {
        "benchmark": "shadows",
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
            "threads": list(threads),
        },
        "results": results,
        "target": target_entry(results, max(threads)),
    }
    print(format_table(doc))
    plot(doc, Path(args.out) / f"shadows-{machine['slug']}.png")
    return doc


def summarise(key: tuple[int, int, str, str], measured: list[dict[str, Any]]) -> dict[str, Any]:
    n, t, light, filter_ = key
    gpu = [m["gpu_ms"] for m in measured if m["gpu_ms"] is not None]
    return {
        "entities": n,
        "threads": t,
        "light": light,
        "filter": filter_,
        "cpu_ms": min(m["cpu_ms"] for m in measured),
        "gpu_ms": min(gpu) if gpu else None,
        "runs": [{"cpu_ms": m["cpu_ms"], "gpu_ms": m["gpu_ms"]} for m in measured],
    }


def target_entry(results: list[dict[str, Any]], threads: int) -> dict[str, Any]:
    by = {(r["entities"], r["threads"], r["light"], r["filter"]): r["cpu_ms"] for r in results}
    shadowed = by.get((TARGET_ENTITIES, threads, "directional", "pcf"))
    base = by.get((TARGET_ENTITIES, threads, "none", "-"))
    return {
        "entities": TARGET_ENTITIES,
        "threads": threads,
        "cpu_ms": shadowed,
        "baseline_cpu_ms": base,
        **ratio_verdict(shadowed, base, TARGET_RATIO),
    }


def format_table(doc: dict[str, Any]) -> str:
    cfg = doc["config"]
    lines = [
        f"shadows at {cfg['width']}x{cfg['height']}: CPU ms / GPU ms, the smaller of 2 runs' medians",
        f"{'entities':>9} {'threads':>7} " + " ".join(f"{light + ' ' + f:>18}" for light, f in CONFIGS),
    ]
    rows: dict[tuple[int, int], dict[tuple[str, str], dict[str, Any]]] = {}
    for r in doc["results"]:
        rows.setdefault((r["entities"], r["threads"]), {})[r["light"], r["filter"]] = r
    for (n, t), cells in sorted(rows.items()):
        text = []
        for key in CONFIGS:
            r = cells.get(key)
            gpu = "-" if r is None or r["gpu_ms"] is None else f"{r['gpu_ms']:.2f}"
            text.append("-" if r is None else f"{r['cpu_ms']:.2f} / {gpu}")
        lines.append(f"{n:>9,} {t:>7} " + " ".join(f"{c:>18}" for c in text))
    tg = doc["target"]
    if tg["ratio"] is not None:
        lines.append(
            f"target: {tg['entities']:,} entities, {tg['threads']} threads, 4 cascades: CPU {tg['cpu_ms']:.2f} ms = "
            f"{tg['ratio']:.2f}x the shadowless {tg['baseline_cpu_ms']:.2f} ms; limit {tg['limit']:.0f}x: "
            f"{'met' if tg['met'] else 'NOT met'}"
        )
    return "\n".join(lines)


def plot(doc: dict[str, Any], path: Path) -> None:
    from . import pyplot, save_figure

    plt = pyplot()
    threads = doc["config"]["threads"]
    fig, axes = plt.subplots(1, len(threads), figsize=(5 * len(threads), 4), squeeze=False)
    for ax, t in zip(axes[0], threads, strict=True):
        for light, filter_ in CONFIGS:
            pts = sorted(
                (r["entities"], r["cpu_ms"])
                for r in doc["results"]
                if r["threads"] == t and r["light"] == light and r["filter"] == filter_
            )
            if pts:
                ax.plot(*zip(*pts), marker="o", label=f"{light} {filter_}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("entities")
        ax.set_ylabel("CPU ms per frame")
        ax.set_title(f"{t} thread{'s' if t > 1 else ''}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path)
