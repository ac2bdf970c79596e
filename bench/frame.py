"""One scene's CPU frame through the run loop, headless: the median and p99 over many frames.

Issue 17's bar: the 1-cube scene (`cube`, the seed's first) at 0.15 ms of CPU a frame, instanced,
one thread, 640x360. The frame is what `ecs-engine run` counts (app/loop.py): the schedule and
the render (extract, write, record, submit), minus the time spent waiting for the GPU's fence.
Small frames need many samples: 2,400 timed frames after 300 of warm-up by default, and
`--repeat` runs the whole configuration again in the same process (the host drifts).
`--frame-reuse both` makes each repeat two runs, with the frames' recordings submitted again
where nothing changed (render/frame/replay.py, the default) and with every frame recorded,
one after the other: the two compared under the same drift. The target is judged on the first.
`--through app` runs the scene as a game through `App` (DefaultPlugins without the perf lines, the
scene's builder as the startup system), to hold the App to the loop's cost.

JSON (schema_version 1): {"benchmark": "frame", "quick", "machine", "device", "config": {"scene",
"mode", "threads", "width", "height", "frames", "warmup", "repeat", "frame_reuse", "through"}, "results":
[{"run", "frame_reuse", "replayed" (the share of timed frames submitted again), "cpu_ms_median",
"cpu_ms_p99", "cpu_ms_mean", "record_ms_median", "gpu_ms_median", "fps", "draws", "python_loop_ns"
(the core's speed before and after the run: ns per iteration of a fixed Python loop, machine.py)}],
"targets": [{"name", "target", "measured", "unit", "op", "met"}]}.

Standalone, `python3 bench/frame.py [options]` measures with whichever ecs_engine is importable
(an older install too, for old/new runs alternated) and prints the table only.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from typing import Any

import numpy as np

from ecs_engine.app.loop import run as run_scene
from ecs_engine.app.scenes import SCENES
from ecs_engine.app.settings import RunOptions
from ecs_engine.render.frame.renderer import MODES

try:
    from .machine import python_loop_ns, standalone
except ImportError:  # run as a script (the standalone use below)
    from machine import python_loop_ns, standalone  # type: ignore[import-not-found,no-redef]

THREADS = 1
TARGET_MS = 0.15  # issue 17: the 1-cube scene, instanced, one thread


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scene", default="cube", choices=SCENES, help="demo scene (default: cube, one cube)")
    parser.add_argument("--mode", default="instanced", choices=MODES)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--size", default="640x360", help="WIDTHxHEIGHT of the offscreen target")
    parser.add_argument("--frames", type=int, default=2400, help="timed frames (default 2,400)")
    parser.add_argument("--warmup", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=1, help="runs of the configuration, one after another")
    parser.add_argument(
        "--frame-reuse",
        default="on",
        choices=("on", "off", "both"),
        help="submit unchanged frames' recordings again (on, the default), record every frame (off), "
        "or each repeat both ways, one after the other",
    )
    parser.add_argument(
        "--through",
        default="loop",
        choices=("loop", "app"),
        help="run the scene as the demo does (loop, the default) or as a game through App (app: DefaultPlugins, "
        "the scene's builder as a startup system)",
    )


def through_app(options: RunOptions) -> Any:
    """The scene as a game through `App` would run it: DefaultPlugins (without the perf lines),
    the demo scene's builder as the startup system, `app.run` headless."""
    from ecs_engine import App, DefaultPlugins
    from ecs_engine.app.plugins import PerfPlugin
    from ecs_engine.app.scenes import scene_builder
    from ecs_engine.render.assets.meshes import Meshes

    build = scene_builder(options.scene)
    app = App(title=options.scene, size=(options.width, options.height))
    app.add_plugins(DefaultPlugins.without(PerfPlugin))
    app.add_startup_systems(lambda world, dt: build(world, world.resources[Meshes].add))
    return app.run(
        frames=options.frames,
        headless=True,
        mode=options.mode,
        threads=options.threads,
        frame_reuse=options.frame_reuse,
    )


def measure(options: RunOptions, warmup: int, through: str = "loop") -> dict[str, Any]:
    before = python_loop_ns()
    result = through_app(options) if through == "app" else run_scene(options)
    after = python_loop_ns()
    cpu = np.array(result.cpu_ms[warmup:])
    gpu = np.array(result.gpu_ms[warmup:])
    record = np.array(result.record_ms[warmup:])
    return {
        "cpu_ms_median": float(np.median(cpu)),
        "cpu_ms_p99": float(np.percentile(cpu, 99)),
        "cpu_ms_mean": float(cpu.mean()),
        "record_ms_median": float(np.median(record)),
        "gpu_ms_median": float(np.median(gpu)) if len(gpu) else None,
        "fps": float(result.fps_after(warmup)),
        "draws": result.last_stats.draws,
        "replayed": float(np.mean(getattr(result, "replayed", [False])[warmup:] or [False])),  # share of frames
        "device": result.device,
        "python_loop_ns": [before, after],  # the core's speed before and after (bench/machine.py)
    }


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    width, height = (int(v) for v in args.size.lower().split("x"))
    frames, warmup, repeat = (60, 10, 1) if args.quick else (args.frames, args.warmup, args.repeat)
    if args.quick:
        width, height = 160, 90
    options = RunOptions(
        scene=args.scene,
        width=width,
        height=height,
        frames=warmup + frames,
        quiet=True,
        mode=args.mode,
        threads=args.threads,
    )
    ways = {"on": [True], "off": [False], "both": [True, False]}[args.frame_reuse]
    results = []
    progress.total = repeat * len(ways)
    for i in range(repeat):
        for reuse in ways:
            what = f"{args.scene}, {args.mode}, {args.threads} thread(s), {width}x{height}: run {i + 1}"
            with progress.step(what + ("" if reuse else ", every frame recorded")):
                run_options = options if reuse else replace(options, frame_reuse=False)  # (older engines: on only)
                through = getattr(args, "through", "loop")
                results.append(measure(run_options, warmup, through) | {"run": i + 1, "frame_reuse": reuse})
    device = results[0].pop("device")
    for r in results[1:]:
        r.pop("device")
    medians = [r["cpu_ms_median"] for r in results if r["frame_reuse"] == ways[0]]
    targets = []
    if args.scene == "cube" and args.mode == "instanced" and args.threads == 1:
        measured = float(np.median(medians))
        targets.append(
            {
                "name": "1-cube scene: CPU frame ms (median), instanced, 1 thread",
                "target": TARGET_MS,
                "measured": measured,
                "unit": "ms",
                "op": "<=",
                "met": bool(measured <= TARGET_MS),
            }
        )
    print(
        f"{'run':>3} {'reuse':>5} {'cpu median ms':>13} {'cpu p99 ms':>10} {'cpu mean ms':>11} {'record ms':>9} "
        f"{'gpu ms':>7} {'loop ns':>11}"
    )
    for r in results:
        gpu = "n/a" if r["gpu_ms_median"] is None else f"{r['gpu_ms_median']:.3f}"
        print(
            f"{r['run']:3} {'on' if r['frame_reuse'] else 'off':>5} {r['cpu_ms_median']:13.4f} {r['cpu_ms_p99']:10.4f} "
            f"{r['cpu_ms_mean']:11.4f} {r['record_ms_median']:9.4f} {gpu:>7} "
            f"{r['python_loop_ns'][0]:5.1f}/{r['python_loop_ns'][1]:5.1f}"
        )
    print(
        f"{args.scene}, {args.mode}, {args.threads} thread(s), {width}x{height}, {frames:,} frames: "
        f"CPU frame median {np.median(medians):.4f} ms (frame reuse {'on' if ways[0] else 'off'})"
    )
    if len(ways) == 2:
        off = float(np.median([r["cpu_ms_median"] for r in results if not r["frame_reuse"]]))
        print(f"every frame recorded: CPU frame median {off:.4f} ms")
    for t in targets:
        print(f"target {'MET ' if t['met'] else 'MISS'} {t['name']}: {t['measured']:.4f} ms (target <= {t['target']})")
    return {
        "benchmark": "frame",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": device,
        "config": {
            "scene": args.scene,
            "mode": args.mode,
            "threads": args.threads,
            "width": width,
            "height": height,
            "frames": frames,
            "warmup": warmup,
            "repeat": repeat,
            "frame_reuse": args.frame_reuse,
            "through": getattr(args, "through", "loop"),
        },
        "results": results,
        "targets": targets,
    }


def main(argv: list[str] | None = None) -> int:
    return standalone(__doc__, add_arguments, run, argv)


if __name__ == "__main__":
    sys.exit(main())
