"""Soak: the editor's scene headless for many frames, entities spawned and destroyed every frame,
the settings switched every few hundred frames; resident memory and GPU memory sampled along the
way. A leak shows as a slope: both must stay flat, and no validation message may arrive.

Per frame: the default schedule (fixed step), SPAWN new cubes and the SPAWN oldest destroyed
(the count stays level), the editor's UI built when imgui-bundle is there (rate-limited as in a
real run), one frame rendered. Every `switch_every` frames the next of SWITCHES is applied
through `Session.apply`, as the editor's requests are: render path and recorder, threads,
culling, and the scene (a new world). RSS from psutil; GPU memory from the device allocator
(bytes in use and reserved). Slopes, in MiB per 1,000 frames, are over the samples after the
warm-up (`warmup_frames`: the first half of the run, and at least until every configuration of
the switch cycle has run once and the cycle is back where it began), and are robust slopes
(`slope_per_1k`: the median of five parts' Theil-Sen slopes): resident memory rises in steps
while pipelines, native recorders, caches and the allocator's arenas for new worker threads
reach their working size, and later steps or bumps by up to ~9 MiB as the allocator keeps or
returns pages. A least-squares line over the last four fifths of 20,000 frames read that as
+0.16 and +0.90 MiB per 1,000 frames in two runs on lavapipe with no leak (the target is 0.5;
this measure: +0.04 and +0.07); a leak rises frame after frame, in every part, and the median
slope is its rate. `--quick` (1,500 frames) churns without switching unless given --switch-every
(`plan`): too short to tell a slope of 0.5 MiB per 1,000 frames while switching.

JSON (schema_version 1): {"benchmark": "soak", "quick", "machine", "device", "config": {"frames",
"spawn", "switch_every", "sample_every", "warmup_frames", "size", "editor", "validate"}, "samples": [{"frame",
"rss_mib", "gpu_used_mib", "gpu_reserved_mib", "entities", "settings"}], "slopes":
{"rss_mib_per_1k_frames", "gpu_used_mib_per_1k_frames", "gpu_reserved_mib_per_1k_frames"},
"growth": {"rss_mib", "python_blocks"} (last sample minus the first after warm-up), "gpu_used_mib"
(the largest of each configuration's last sample minus its first: the memory differs by setting), "switches",
"validation_messages", "wall_s", "targets": [...]}.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import psutil

from ecs_engine.components import Mesh, Transform, Velocity

THREADS = 4
SPAWN = 20  # entities spawned and destroyed each frame
# Each switch is applied on top of the settings in force; the scene switches go both ways.
SWITCHES: list[dict[str, Any]] = [
    {"mode": "per_entity"},
    {"threads": 2},
    {"mode": "indirect"},
    {"culling": False},
    {"scene": "cube"},
    {"mode": "instanced", "recorder": "python"},
    {"threads": THREADS, "culling": True},
    {"scene": "grid100", "recorder": "native"},
]
FLAT_RSS_MIB_PER_1K = 0.5  # a leak of ~0.5 KiB a frame would show as this
FLAT_GPU_MIB_PER_1K = 0.0
SWITCH_EVERY = 300  # the default run's; --quick switches only when given --switch-every


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--frames", type=int, help="frames to run (default 100,000; --quick 1,500)")
    parser.add_argument(
        "--switch-every",
        type=int,
        help=f"frames between settings switches (default {SWITCH_EVERY}; --quick: none unless given)",
    )
    parser.add_argument("--no-validate", dest="validate", action="store_false", help="without validation layers")


def plan(args: argparse.Namespace) -> tuple[int, int, int]:
    """Frames, frames between switches (more than the frames: none) and warm-up frames.

    --quick without --switch-every does not switch: resident memory differs between
    configurations by a few MiB, and freeing one configuration's memory leaves the allocator free
    pages that hide a leak from RSS for a while; in 750 measured frames that reads as several MiB
    per 1,000 frames either way. A run that switches must be long (the default, or --frames
    20000) for a slope to mean anything."""
    frames = args.frames or (1_500 if args.quick else 100_000)
    no_switches = frames + 1
    switch_every = max(1, args.switch_every or (no_switches if args.quick else SWITCH_EVERY))
    return frames, switch_every, warmup_frames(frames, switch_every)


def preflight(args: argparse.Namespace) -> None:
    """Refuse a run whose frames all fall in the warm-up: it would measure nothing."""
    from ecs_engine.errors import UsageError

    frames, switch_every, warmup = plan(args)
    if frames < 1:
        raise UsageError(f"--frames {frames}: at least 1")
    if frames - warmup < 10:
        raise UsageError(
            f"{frames:,} frames end within the warm-up ({warmup:,} frames with a switch every {switch_every:,}): "
            "run more frames or switch more often"
        )


def warmup_frames(frames: int, switch_every: int) -> int:
    """Frames left out of the slopes: the first half of the run, and with switches at least one
    whole cycle of them and one interval more (every configuration's first use is warm-up)."""
    cycle = (len(SWITCHES) + 1) * switch_every
    return max(frames // 2, cycle) if switch_every < frames else frames // 2


SLOPE_PARTS = 5  # a step or bump in up to two of the five parts leaves the median slope flat


def slope_per_1k(frames: np.ndarray, values: np.ndarray) -> float:
    """Per 1,000 frames: the median of the Theil-Sen slopes of SLOPE_PARTS consecutive parts
    of the samples (fewer with few samples). A leak rises in every part; a step in one part or
    a bump that comes and goes does not move the median. 0.0 with fewer than 2 frames."""
    parts = max(1, min(SLOPE_PARTS, len(frames) // 4))
    return float(np.median([theil_sen(frames[p], values[p]) for p in np.array_split(np.arange(len(frames)), parts)]))


def theil_sen(frames: np.ndarray, values: np.ndarray) -> float:
    """The median of the slopes between every two samples, per 1,000 frames."""
    if len(frames) < 2 or np.ptp(frames) == 0:
        return 0.0
    i, j = np.triu_indices(len(frames), 1)
    apart = frames[j] - frames[i]
    keep = apart != 0
    return float(np.median((values[j] - values[i])[keep] / apart[keep]) * 1000.0)


def churn(world: Any, spawned: list[np.ndarray], rng: np.random.Generator) -> None:
    """SPAWN new cubes that drift, and the oldest SPAWN destroyed once ten frames' worth live."""
    handle = 0
    for batch in world.query(Mesh, write=()):
        if len(batch):
            handle = int(batch[Mesh].handle[0])
            break
    spawned.append(
        world.spawn_batch(
            SPAWN,
            Transform(position=rng.uniform(-4, 4, (SPAWN, 3)), scale=(0.2, 0.2, 0.2)),
            Velocity(linear=rng.normal(0.0, 0.5, (SPAWN, 3))),
            Mesh(handle=handle, material=rng.integers(0, 6, SPAWN, dtype=np.uint32)),
        )
    )
    if len(spawned) > 10:
        world.destroy(spawned.pop(0))


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    from ecs_engine.app.offscreen import OffscreenSource
    from ecs_engine.app.perf import PerfMonitor
    from ecs_engine.app.report import describe_device
    from ecs_engine.app.session import Session
    from ecs_engine.app.settings import FIXED_DT, RunOptions

    frames, switch_every, warmup = plan(args)
    sample_every = max(1, frames // 200)
    size = (320, 240) if args.quick else (640, 360)
    editor_ok = importlib.util.find_spec("imgui_bundle") is not None
    options = RunOptions(scene="grid100", width=size[0], height=size[1], validate=args.validate, threads=THREADS)
    source = OffscreenSource()
    process = psutil.Process()
    samples: list[dict[str, Any]] = []
    rng = np.random.default_rng(3)
    switches = 0
    progress.total = 10
    with Session(options, source) as session:
        editor = None
        if editor_ok:
            from ecs_engine.app.editor_session import EditorSession

            editor = EditorSession(session, ("grid100", "cube"), THREADS)
        spawned: list[np.ndarray] = []
        perf = PerfMonitor()  # what the editor's Perf window shows
        stats = None
        session.on_world.append(lambda world: spawned.clear())  # a new scene: its own entities
        start = time.perf_counter()
        try:
            for i in range(frames):
                if i and i % switch_every == 0:
                    session.apply(replace(session.settings, **SWITCHES[switches % len(SWITCHES)]))
                    switches += 1
                t0 = time.perf_counter()
                session.schedule.run_frame(session.world, FIXED_DT, source.clock)
                churn(session.world, spawned, rng)
                if editor is not None:
                    editor.build(session.world, stats, perf, FIXED_DT, *size)
                stats = session.renderer.render(session.world)
                perf.frame(
                    (time.perf_counter() - t0) * 1e3 - stats.wait_ms,
                    stats.record_ms,
                    stats.gpu_ms,
                    stats.wait_ms,
                    draws=stats.draws,
                    visible=stats.instances,
                )
                if i % sample_every == 0 or i == frames - 1:
                    memory = session.device.allocator.stats()
                    s = session.settings
                    samples.append(
                        {
                            "frame": i,
                            "rss_mib": process.memory_info().rss / 2**20,
                            "python_blocks": sys.getallocatedblocks(),
                            "gpu_used_mib": memory["used_bytes"] / 2**20,
                            "gpu_reserved_mib": memory["reserved_bytes"] / 2**20,
                            "entities": len(session.world),
                            "settings": f"{s.scene} {s.mode} {s.recorder} {s.threads}t culling={s.culling}",
                        }
                    )
                if (i + 1) % max(1, frames // 10) == 0:
                    progress.done += 1
                    last = samples[-1]
                    progress.note(
                        f"frame {i + 1:,}: rss {last['rss_mib']:.1f} MiB, GPU {last['gpu_used_mib']:.2f} MiB "
                        f"used, {last['entities']:,} entities"
                    )
            session.device.wait_idle()
        finally:
            if editor is not None:
                editor.destroy()
        wall = time.perf_counter() - start
        device = describe_device(session.device)
    messages = source.validation_messages()
    steady = [s for s in samples if s["frame"] >= warmup]
    f = np.array([s["frame"] for s in steady], dtype=np.float64)
    slopes = {
        f"{k}_per_1k_frames": slope_per_1k(f, np.array([s[k] for s in steady]))
        for k in ("rss_mib", "python_blocks", "gpu_used_mib", "gpu_reserved_mib")
    }
    growth = {k: steady[-1][k] - steady[0][k] for k in ("rss_mib", "python_blocks")} if steady else {}
    # GPU memory depends on the settings (the indirect path's buffers, which meshes are merged):
    # compare each configuration's first and last sample after warm-up
    by_settings: dict[str, list[float]] = {}
    for s in steady:
        by_settings.setdefault(s["settings"], []).append(s["gpu_used_mib"])
    growth["gpu_used_mib"] = max((v[-1] - v[0] for v in by_settings.values()), default=0.0)
    targets = [
        {
            "name": "resident memory flat after warm-up",
            "measured": slopes["rss_mib_per_1k_frames"],
            "target": FLAT_RSS_MIB_PER_1K,
            "unit": "MiB per 1k frames",
            "op": "<=",
            "met": slopes["rss_mib_per_1k_frames"] <= FLAT_RSS_MIB_PER_1K,
        },
        {
            "name": "GPU memory in use flat after warm-up",
            "measured": growth.get("gpu_used_mib", 0.0),
            "target": FLAT_GPU_MIB_PER_1K,
            "unit": "MiB (last minus first)",
            "op": "<=",
            "met": growth.get("gpu_used_mib", 0.0) <= FLAT_GPU_MIB_PER_1K,
        },
        {
            "name": "validation messages",
            "measured": len(messages),
            "target": 0,
            "unit": "messages",
            "op": "<=",
            "met": not messages,
        },
    ]
    doc = {
        "benchmark": "soak",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": device,
        "config": {
            "frames": frames,
            "spawn": SPAWN,
            "switch_every": switch_every,
            "sample_every": sample_every,
            "warmup_frames": warmup,
            "size": list(size),
            "editor": editor is not None,
            "validate": bool(args.validate),
        },
        "samples": samples,
        "slopes": slopes,
        "growth": growth,
        "switches": switches,
        "validation_messages": len(messages),
        "first_messages": messages[:5],
        "wall_s": wall,
        "targets": targets,
    }
    print(
        f"{frames:,} frames in {wall:.1f} s, {switches} settings switches, editor {'on' if editor else 'off'}: "
        f"rss {slopes['rss_mib_per_1k_frames']:+.3f} MiB per 1k frames (grew {growth.get('rss_mib', 0):+.1f} MiB), "
        f"GPU in use {slopes['gpu_used_mib_per_1k_frames']:+.4f} MiB per 1k frames, "
        f"{len(messages)} validation messages"
    )
    plot(doc, Path(args.out) / f"soak-{machine.get('slug', 'local')}.png")
    for t in targets:
        print(
            f"target {'MET ' if t['met'] else 'MISS'} {t['name']}: {t['measured']:.3g} {t['unit']} "
            f"(target {t['op']} {t['target']})"
        )
    return doc


def plot(doc: dict[str, Any], path: Path) -> None:
    """Resident and GPU memory against frames, the settings switches marked."""
    from . import pyplot, save_figure

    plt = pyplot()
    frames = [s["frame"] for s in doc["samples"]]
    fig, (rss, gpu) = plt.subplots(1, 2, figsize=(12, 4))
    rss.plot(frames, [s["rss_mib"] for s in doc["samples"]])
    rss.set_ylabel("resident memory, MiB")
    gpu.plot(frames, [s["gpu_used_mib"] for s in doc["samples"]], label="in use")
    gpu.plot(frames, [s["gpu_reserved_mib"] for s in doc["samples"]], label="reserved")
    gpu.set_ylabel("GPU memory, MiB")
    gpu.legend()
    every = doc["config"]["switch_every"]
    for ax in (rss, gpu):
        ax.axvspan(0, doc["config"]["warmup_frames"], color="0.93", zorder=0, label="warm-up (not measured)")
        ax.set_xlabel("frame")
        for x in range(every, frames[-1] + 1, every) if frames else ():
            ax.axvline(x, color="0.85", linewidth=0.5, zorder=0)
        ax.grid(True, alpha=0.3)
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path)
