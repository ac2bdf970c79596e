"""Temporal-coherence culling against per-frame frustum culling (CPU only, one thread).

The scene: N cubes in a 600-unit box, 90% still and 10% moving (Velocity, up to 3 units/s), a
camera with SpeedLimits of 20 units/s and 2 rad/s. Camera paths, 180 frames at 60 Hz each, made
from a seed (the same every run):
- walk: forward at 80% of the limit, turning slowly;
- fast-turn: standing, turning at 95% of the limit;
- speed-changes: forward at the limit or still, switching every half second, pitching;
- teleport: the walk, with a 150-unit jump every second;
- still: the camera does not move (only the moving cubes are due).

Per frame both culls run on the same world: `frustum` tests every row (the renderer's culling
kernel, instance_rows.cull_views, one view), `temporal` is TemporalCulling.masks plus the keys
of what it keeps (masked_keys). Reported per (path, N, min_interval): median ms of each, the
rows temporal tested, its false negatives (rows exact culling draws that it culled: must be 0)
and its extra draws (rows it draws that exact culling culls: 0 unless min_interval holds rows).
min_interval trades extra draws for fewer tests; the plot is extra draws against CPU ms.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Mesh, Transform, Velocity
from ecs_engine.maths.camera import yaw_pitch_quat
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.culling import TemporalCulling
from ecs_engine.render.culling.temporal_culling import SpeedLimits
from ecs_engine.render.draw.instance_rows import cull_views, masked_keys, padded_planes
from ecs_engine.render.extract.frame_data import FrameExtractor

LIMITS = SpeedLimits(move=20.0, turn=2.0)
DT = 1.0 / 60.0
PATHS = ("walk", "fast-turn", "speed-changes", "teleport", "still")
INTERVALS = (0.0, 1 / 30, 0.1, 0.25)


def camera_path(name: str, frames: int) -> np.ndarray:
    """(frames, 5): x, y, z, yaw, pitch per frame."""
    out = np.zeros((frames, 5))
    pos, yaw, pitch = np.zeros(3), 0.0, 0.0
    for f in range(frames):
        speed, turn = 0.8 * LIMITS.move, 0.2
        if name == "fast-turn":
            speed, turn = 0.0, 0.95 * LIMITS.turn
        elif name == "still":
            speed, turn = 0.0, 0.0
        elif name == "speed-changes":
            speed, turn = (LIMITS.move if (f // 30) % 2 == 0 else 0.0), 0.3
            pitch = 0.3 * math.sin(f * DT * 2.0)
        yaw += turn * DT
        forward = np.array([-math.sin(yaw) * math.cos(pitch), math.sin(pitch), -math.cos(yaw) * math.cos(pitch)])
        pos = pos + forward * speed * DT
        if name == "teleport" and f % 60 == 59:
            pos = pos + np.array([150.0, 0.0, -150.0])
        out[f] = (*pos, yaw, pitch)
    return out


def make_world(n: int) -> World:
    rng = np.random.default_rng(5)
    world = World()
    world.resources[SpeedLimits] = LIMITS
    still = n - n // 10
    world.spawn_batch(still, Transform(position=rng.uniform(-300, 300, (still, 3))), Mesh(handle=0))
    moving = n // 10
    heading = rng.normal(size=(moving, 3))
    world.spawn_batch(
        moving,
        Transform(position=rng.uniform(-300, 300, (moving, 3))),
        Velocity(linear=heading / np.linalg.norm(heading, axis=1)[:, None] * rng.uniform(0, 3, (moving, 1))),
        Mesh(handle=0),
    )
    world.spawn(Transform(), Camera(fov_y=math.radians(60.0), near=0.1))
    return world


def run_path(n: int, path: str, frames: int, min_interval: float) -> dict[str, Any]:
    world = make_world(n)
    camera = world.query(Camera).entities()[0]
    mesh = cube_mesh()
    bounds = (np.array([mesh.center], np.float64), np.array([mesh.radius], np.float64), np.array([36]))
    schedule, extractor = default_schedule(), FrameExtractor(lambda: 1, chunk_rows=1 << 30)
    temporal = TemporalCulling(min_interval)  # the culling method, timed apart from the extraction
    frustum_ms, temporal_ms, tested, missed, extra, visible = [], [], [], 0, [], []
    for x, y, z, yaw, pitch in camera_path(path, frames):
        world.set(int(camera), Transform, position=np.array([x, y, z]), rotation=yaw_pitch_quat(yaw, pitch))
        schedule.run(world, DT)
        data = extractor.extract(world, 16 / 9, 1, "frustum")
        planes = padded_planes([data.planes])
        exact = []
        t0 = time.perf_counter()
        for chunk in data.chunks:
            keys = np.empty((1, len(chunk.handle)), np.int32)
            cull_views(chunk.model, chunk.handle, bounds[0], bounds[1], planes, keys, np.zeros((1, 2), np.int64))
            exact.append(keys[0] >= 0)
        t1 = time.perf_counter()
        masks = temporal.masks(world, data.camera, data.origin, data.planes, DT, bounds)
        assert masks is not None
        drawn = []
        for chunk in data.chunks:
            mask = masks[chunk.table][chunk.start : chunk.start + len(chunk.handle)]
            keys = masked_keys(chunk.model, chunk.handle, mask, np.zeros(2, np.int64))
            drawn.append(keys >= 0)
        t2 = time.perf_counter()
        e, d = np.concatenate(exact), np.concatenate(drawn)
        frustum_ms.append((t1 - t0) * 1e3)
        temporal_ms.append((t2 - t1) * 1e3)
        tested.append(temporal.culler.stats.tested)
        missed += int((e & ~d).sum())
        extra.append(int((d & ~e).sum()))
        visible.append(int(e.sum()))
    skip = 2  # the first frames compile and test everything
    return {
        "path": path,
        "entities": n,
        "min_interval_s": round(min_interval, 4),
        "frustum_ms": round(statistics.median(frustum_ms[skip:]), 4),
        "temporal_ms": round(statistics.median(temporal_ms[skip:]), 4),
        "temporal_p99_ms": round(float(np.percentile(temporal_ms[skip:], 99)), 4),
        "tested_per_frame": round(statistics.mean(tested[skip:]), 1),
        "visible_per_frame": round(statistics.mean(visible), 1),
        "false_negatives": missed,
        "extra_draws_per_frame": round(statistics.mean(extra), 2),
    }


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--frames", type=int, default=180, help="frames per camera path")
    parser.add_argument("--plot", metavar="JSON", help="only draw the plot of an earlier run's JSON, beside it")
    parser.add_argument("--entities", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any] | None:
    if args.plot:
        import json

        source = Path(args.plot)
        plot(json.loads(source.read_text()), source.with_suffix(".png"))
        print(f"wrote {source.with_suffix('.png')}")
        return None
    counts = [2_000] if args.quick else args.entities
    frames = 20 if args.quick else args.frames
    paths = PATHS[:2] if args.quick else PATHS
    intervals = INTERVALS[:2] if args.quick else INTERVALS
    rows = []
    for n in counts:
        for path in paths:
            for interval in intervals:
                with progress.step(f"{n:,} entities, {path}, min_interval {interval:.3f} s"):
                    rows.append(run_path(n, path, frames, interval))
    missed = sum(r["false_negatives"] for r in rows)
    if missed:
        raise AssertionError(f"temporal culling culled {missed} rows that exact culling draws")
    print(
        f"{'entities':>9} {'path':14} {'hold s':>7} {'frustum ms':>10} {'temporal ms':>11} {'tested':>9} {'extra':>8}"
    )
    for r in rows:
        print(
            f"{r['entities']:>9,} {r['path']:14} {r['min_interval_s']:7.3f} {r['frustum_ms']:10.3f} "
            f"{r['temporal_ms']:11.3f} {r['tested_per_frame']:9.0f} {r['extra_draws_per_frame']:8.1f}"
        )
    doc = {"benchmark": "culling", "machine": machine, "quick": bool(args.quick), "frames": frames, "rows": rows}
    doc["limits"] = {"move": LIMITS.move, "turn": LIMITS.turn}
    out = Path(args.out) / f"culling-{machine['slug']}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    try:
        plot(doc, out)
        doc["plot"] = out.name
    except ImportError:  # a machine without the bench extra: `python -m bench culling --plot JSON` later
        progress.note("matplotlib is missing: no plot (install the bench extra, then run with --plot)")
        doc["plot"] = None
    return doc


def plot(doc: dict[str, Any], path: Path) -> None:
    from . import pyplot, save_figure

    plt = pyplot()
    counts = sorted({r["entities"] for r in doc["rows"]})
    fig, axes = plt.subplots(1, len(counts), figsize=(6 * len(counts), 4.4), squeeze=False)
    for ax, n in zip(axes[0], counts):
        rows = [r for r in doc["rows"] if r["entities"] == n]
        for name in dict.fromkeys(r["path"] for r in rows):
            rr = sorted((r for r in rows if r["path"] == name), key=lambda r: r["min_interval_s"])
            ax.plot([r["temporal_ms"] for r in rr], [r["extra_draws_per_frame"] for r in rr], marker="o", label=name)
            for r in rr:
                ax.annotate(f"{r['min_interval_s']:.2g}s", (r["temporal_ms"], r["extra_draws_per_frame"]), fontsize=7)
        frustum = statistics.median(r["frustum_ms"] for r in rows)
        ax.axvline(frustum, color="grey", linestyle="--", label="per-frame frustum")
        ax.set_xlabel("CPU ms a frame (1 thread)")
        ax.set_ylabel("extra draws a frame (false negatives: 0)")
        ax.set_title(f"{n:,} entities")
        ax.legend(fontsize=8)
    save_figure(fig, path)
