"""The seed's three scenes (1 cube, 100 cubes, OBJ model) headless, beside the seed's Tables 4.1-4.3.

Per scene: warm-up frames, then timed frames with the default schedule and renderer; FPS from
the wall clock; CPU frame ms (frame start to submit); GPU frame ms from timestamp queries at the
start and end of the frame's command buffer; CPU system % and process % from psutil over the
timed frames (process % raw and per core). Each scene runs in both recording modes
(`instanced`, `per_entity`) with one thread (the seed's single-threaded column) and with every
core (its multi-threaded column), with the default recorder (native when numba is installed).

JSON (schema_version 1): {"benchmark": "seed-tables", "quick", "machine", "device",
"config": {"width", "height", "warmup", "frames"}, "results": [{"scene", "mode", "threads",
"frames", "fps", "cpu_ms_mean", "cpu_ms_p99", "gpu_ms_mean", "gpu_ms_p99", "cpu_system_percent",
"cpu_process_percent", "cpu_process_percent_per_core", "draws", "triangles"}], "seed": {...},
"overlay": {"scene", "mode", "threads", "cpu_ms_off", "cpu_ms_on", "difference_ms", "ui_ms_mean",
"target_ms", "met"}, "windowed": {"skipped": why} | {"rows": [the results' fields, "window": true,
"present"]}}

Windowed rows (instanced, 1 thread, each scene) run only where a display exists, presenting
with vsync off where the surface allows (immediate, else mailbox, else fifo).

The overlay entry is the cost of the ImGui editor and Perf window on the 100-cube scene: runs
with it off and on, alternated twice (the host's drift shows up in both), and the UI's own
measured time (building it, copying its geometry, recording it).
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import psutil

from ecs_engine.app.loop import run as run_scene
from ecs_engine.app.scenes import SEED_SCENES
from ecs_engine.app.settings import RunOptions
from ecs_engine.jobs import default_threads
from ecs_engine.render.frame.renderer import MODES as RENDER_MODES

THREADS = default_threads()
SCENES = SEED_SCENES  # the seed thesis measured these three
MODES = RENDER_MODES  # every mode the renderer has

# The seed thesis (i7-11800H, RTX 3070, Windows 11): Tables 4.1, 4.2 and 4.3,
# (single-threaded, multi-threaded).
SEED = {
    "cube": {
        "fps": (580, 600),
        "cpu_ms": (1.7, 1.6),
        "gpu_ms": (0.01, 0.01),
        "cpu_system": (4.1, 3.2),
        "cpu_process": (0.5, 0.3),
    },
    "grid100": {
        "fps": (280, 420),
        "cpu_ms": (3.5, 2.4),
        "gpu_ms": (0.02, 0.02),
        "cpu_system": (6.3, 4.5),
        "cpu_process": (0.9, 0.5),
    },
    "model": {
        "fps": (190, 322),
        "cpu_ms": (5.2, 3.1),
        "gpu_ms": (0.05, 0.05),
        "cpu_system": (8.5, 5.6),
        "cpu_process": (1.4, 0.7),
    },
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)


OVERLAY_TARGET_MS = 0.3


def measure(
    scene: str,
    width: int,
    height: int,
    warmup: int,
    frames: int,
    mode: str = "instanced",
    threads: int = 1,
    editor: bool = False,
    glfw: Any = None,
) -> dict[str, Any]:
    """One configuration; with `glfw` (an opened GLFW module) in a window, presenting with
    vsync off (immediate, else mailbox, else fifo: whatever the surface offers)."""
    proc = psutil.Process()
    psutil.cpu_percent(None)
    proc.cpu_percent(None)
    t0 = time.perf_counter()
    options = RunOptions(
        scene=scene,
        width=width,
        height=height,
        frames=warmup + frames,
        quiet=True,
        mode=mode,
        threads=threads,
        editor=editor,
    )
    present = None
    if glfw is None:
        result = run_scene(options)
    else:
        from ecs_engine.app.window import run_windowed
        from ecs_engine.errors import UsageError

        for present in ("immediate", "mailbox", "fifo"):
            try:
                result = run_windowed(replace(options, present=present), glfw)
                break
            except UsageError as exc:
                if "present mode" not in str(exc) or present == "fifo":
                    raise
            glfw = _reopen(glfw)
    system = psutil.cpu_percent(None)
    process = proc.cpu_percent(None)
    wall = time.perf_counter() - t0
    cpu = np.array(result.cpu_ms[warmup:])
    gpu = np.array(result.gpu_ms[warmup:]) if len(result.gpu_ms) > warmup else np.array(result.gpu_ms)
    stats = result.last_stats
    cores = psutil.cpu_count() or 1
    return {
        "scene": scene,
        "mode": mode,
        "threads": threads,
        "frames": frames,
        "fps": float(result.fps_after(warmup)),  # wall clock over the timed frames
        "cpu_ms_mean": float(cpu.mean()),
        "cpu_ms_p99": float(np.percentile(cpu, 99)),
        "gpu_ms_mean": float(gpu.mean()) if len(gpu) else None,
        "gpu_ms_p99": float(np.percentile(gpu, 99)) if len(gpu) else None,
        "record_ms_mean": float(result.record_ms_mean(warmup)),
        "cpu_system_percent": float(system),
        "cpu_process_percent": float(process),
        "cpu_process_percent_per_core": float(process / cores),
        "draws": stats.draws,
        "triangles": stats.triangles,
        "entities_drawn": stats.instances,
        "device": result.device,
        "validation_messages": len(result.validation_messages),
        "run_wall_s": wall,
        "editor": editor,
        "window": glfw is not None,
        "present": present,
        "ui_ms_mean": float(np.mean(result.ui_ms[warmup:])) if editor else None,
    }


def _reopen(glfw: Any) -> Any:
    from ecs_engine.app.window import open_glfw

    return open_glfw()  # run_windowed terminates GLFW when it ends


def measure_windowed(width: int, height: int, warmup: int, frames: int) -> dict[str, Any]:
    """The seed's scenes in a window (instanced, 1 thread) when a display exists."""
    from ecs_engine.app.window import open_glfw

    if open_glfw() is None:
        return {"skipped": "no display"}
    rows = []
    for scene in SCENES:
        rows.append(measure(scene, width, height, warmup, frames, "instanced", 1, glfw=open_glfw()))
    return {"rows": rows}


def measure_overlay(width: int, height: int, warmup: int, frames: int) -> dict[str, Any]:
    """The editor's CPU cost on the 100-cube frame: off/on alternated twice."""
    runs = {False: [], True: []}
    for editor in (False, True, False, True):
        runs[editor].append(measure("grid100", width, height, warmup, frames, "instanced", 1, editor))
    off = float(np.mean([r["cpu_ms_mean"] for r in runs[False]]))
    on = float(np.mean([r["cpu_ms_mean"] for r in runs[True]]))
    return {
        "scene": "grid100",
        "mode": "instanced",
        "threads": 1,
        "cpu_ms_off": off,
        "cpu_ms_on": on,
        "difference_ms": on - off,
        "ui_ms_mean": float(np.mean([r["ui_ms_mean"] for r in runs[True]])),
        "target_ms": OVERLAY_TARGET_MS,
        "met": bool(on - off <= OVERLAY_TARGET_MS),
    }


def format_table(doc: dict[str, Any]) -> str:
    """Ours beside the seed's, with the ratios (FPS ours/seed; CPU ms seed/ours: above 1 = we
    are faster)."""
    lines = [
        f"{'scene':8} {'mode':10} {'thr':>3} {'FPS':>7} {'seed':>5} {'x':>5} {'CPU ms':>7} {'seed':>5} {'x':>5} "
        f"{'rec ms':>7} {'GPU ms':>7} {'seed':>5} {'sys %':>6} {'proc %':>7} {'seed sys/proc':>14}"
    ]
    for r in doc["results"]:
        s = SEED[r["scene"]]
        col = 0 if r["threads"] == 1 else 1
        gpu = f"{r['gpu_ms_mean']:.3f}" if r["gpu_ms_mean"] is not None else "n/a"
        lines.append(
            f"{r['scene']:8} {r['mode']:10} {r['threads']:3} {r['fps']:7.0f} {s['fps'][col]:5} "
            f"{r['fps'] / s['fps'][col]:5.1f} {r['cpu_ms_mean']:7.3f} {s['cpu_ms'][col]:5} "
            f"{s['cpu_ms'][col] / r['cpu_ms_mean']:5.1f} {r['record_ms_mean']:7.3f} {gpu:>7} "
            f"{s['gpu_ms'][col]:5} {r['cpu_system_percent']:6.1f} {r['cpu_process_percent']:7.1f} "
            f"{s['cpu_system'][col]:>8}/{s['cpu_process'][col]}"
        )
    lines.append(
        "seed: i7-11800H + RTX 3070, Windows 11, Tables 4.1-4.3: 1 thread beside its single-threaded "
        "column, more beside its multi-threaded one (its GPU times read ~0: two adjacent timestamps)"
    )
    return "\n".join(lines)


def plot(doc: dict[str, Any], path: Path) -> None:
    """FPS and CPU ms per scene, ours (each mode) beside the seed's, single- and multi-threaded."""
    from . import pyplot, save_figure

    plt = pyplot()

    fig, axes = plt.subplots(1, 2, figsize=(13, 4.4))
    scenes = list(dict.fromkeys(r["scene"] for r in doc["results"]))
    modes = list(dict.fromkeys(r["mode"] for r in doc["results"]))
    threads = sorted({r["threads"] for r in doc["results"]})
    labels = [f"{sc}\n{'1 thread' if t == 1 else f'{t} threads'}" for sc in scenes for t in threads]
    width = 0.8 / (len(modes) + 1)
    for ax, key, seed_key, title in (
        (axes[0], "fps", "fps", "FPS (wall clock), higher is better"),
        (axes[1], "cpu_ms_mean", "cpu_ms", "CPU ms per frame, lower is better"),
    ):
        for i, mode in enumerate(modes):
            values = [
                next(
                    (r[key] for r in doc["results"] if r["scene"] == sc and r["threads"] == t and r["mode"] == mode),
                    0.0,
                )
                for sc in scenes
                for t in threads
            ]
            ax.bar(np.arange(len(labels)) + i * width, values, width, label=f"ecs_engine {mode}")
        seed = [SEED[sc][seed_key][0 if t == 1 else 1] for sc in scenes for t in threads]
        ax.bar(np.arange(len(labels)) + len(modes) * width, seed, width, label="seed (C++, RTX 3070)", color="gray")
        ax.set_xticks(np.arange(len(labels)) + 0.4 - width / 2, labels, fontsize=8)
        ax.set_title(title)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=7)
    save_figure(fig, path)


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    warmup, frames = (10, 60) if args.quick else (120, 1200)
    width, height = (args.width, args.height) if not args.quick else (320, 240)
    results = []
    thread_counts = sorted({1, THREADS})
    progress.total = len(SCENES) * len(MODES) * len(thread_counts) + 2
    for scene in SCENES:
        for mode in MODES:
            for threads in thread_counts:
                with progress.step(
                    f"{scene} {mode} {threads} threads: {warmup} warm-up + {frames} frames at {width}x{height}"
                ):
                    results.append(measure(scene, width, height, warmup, frames, mode, threads))
    with progress.step("the seed's scenes in a window, if there is a display"):
        windowed = measure_windowed(width, height, warmup, frames)
    with progress.step("editor overlay on and off, 100 cubes, 1 thread, twice each"):
        overlay = measure_overlay(width, height, warmup, frames)
    doc = {
        "benchmark": "seed-tables",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": results[0]["device"],
        "config": {"width": width, "height": height, "warmup": warmup, "frames": frames, "pid": os.getpid()},
        "results": results,
        "seed": SEED,
        "overlay": overlay,
        "windowed": windowed,
    }
    print(format_table(doc))
    out = Path(args.out) / f"seed-tables-{machine['slug']}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    plot(doc, out)
    for r in windowed.get("rows", []):
        print(
            f"windowed {r['scene']:8} instanced 1 thread, present {r['present']}: {r['fps']:.0f} FPS, "
            f"CPU {r['cpu_ms_mean']:.3f} ms, GPU {r['gpu_ms_mean'] or float('nan'):.3f} ms"
        )
    if "skipped" in windowed:
        print(f"windowed rows skipped: {windowed['skipped']}")
    print(
        f"overlay (editor + Perf window), 100 cubes, 1 thread: CPU {overlay['cpu_ms_off']:.3f} ms off, "
        f"{overlay['cpu_ms_on']:.3f} ms on, +{overlay['difference_ms']:.3f} ms (target <= {OVERLAY_TARGET_MS}: "
        f"{'MET' if overlay['met'] else 'MISS'}); the UI's own time {overlay['ui_ms_mean']:.3f} ms"
    )
    return doc
