"""Python bytecodes a frame: what a scene's frame asks of the interpreter (the schedule and the
render), counted instruction by instruction after a warm-up, in all and by module.

A small frame's CPU time moves with the host's core speed (about 2x on the GPU host, between
minutes), so two versions' times compare only run side by side. The count does not move with
it: repeated runs of one tree on the H200 count the same, and runs on the lavapipe host agree
with each other too, so it shows what a change to the per-frame path saves at once, and it runs
without a GPU host. Compare counts made on one machine and Python only: each Python version
compiles to other bytecodes, and the driver chooses some paths. It is not a time: a C call
(NumPy, Vulkan) counts as the one instruction that calls it, and attribute reads on cold objects
cost more on some hosts than on others. Nothing is timed.

Standalone, `python3 bench/bytecodes.py --scene cube` counts with whichever ecs_engine is
importable (an older install too: `PYTHONPATH=/path/to/old python3 bench/bytecodes.py`), which
is how two versions compare.

JSON (schema_version 1): {"benchmark": "bytecodes", "quick", "machine", "config": {"scene",
"width", "height", "warmup", "frames"}, "results": {"per_frame", "schedule_per_frame",
"render_per_frame", "by_module": {module: per frame, largest first}}}.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from typing import Any

from ecs_engine.app.scenes import SCENES

try:
    from .machine import standalone
except ImportError:  # run as a script (the standalone use below)
    from machine import standalone  # type: ignore[import-not-found,no-redef]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scene", default="cube", choices=SCENES, help="demo scene (default: cube, one cube)")
    parser.add_argument("--frames", type=int, default=50, help="counted frames (default 50)")
    parser.add_argument("--warmup", type=int, default=300, help="frames before counting (default 300)")


def _renderer_class() -> Any:
    try:
        from ecs_engine.render.frame.renderer import Renderer
    except ImportError:  # engines before the renderer's sub-packages
        from ecs_engine.render.renderer import Renderer  # type: ignore[no-redef]
    return Renderer


class _Counter:
    """sys.settrace's tracer counting each frame's opcodes by the code's file."""

    def __init__(self) -> None:
        self.by_file: Counter[str] = Counter()

    def trace(self, frame: Any, event: str, arg: Any) -> Any:
        frame.f_trace_opcodes = True
        frame.f_trace_lines = False
        if event == "opcode":
            self.by_file[frame.f_code.co_filename] += 1
        return self.trace

    def total(self) -> int:
        return sum(self.by_file.values())


def _module(filename: str) -> str:
    """A code file as a short name: its path inside ecs_engine (or the folder installed in it)."""
    for mark in ("ecs_engine/", "/components/", "/systems/"):
        if mark in filename:
            tail = filename.split(mark, 1)[1]
            return tail if mark == "ecs_engine/" else mark.strip("/") + "/" + tail
    return filename.rsplit("/", 1)[-1]


def count(scene: str, width: int, height: int, warmup: int, frames: int) -> dict[str, Any]:
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.bench import headless_gpu
    from ecs_engine.ecs.world import World

    with headless_gpu(width, height) as (device, target, meshes):
        world = World()
        scene_builder(scene)(world, meshes.add)
        schedule = default_schedule()
        renderer = _renderer_class()(device, target, meshes)
        try:
            for _ in range(warmup):
                schedule.run(world, 1 / 60)
                renderer.render(world)
            scheduled, rendered = _Counter(), _Counter()
            for _ in range(frames):
                sys.settrace(scheduled.trace)
                schedule.run(world, 1 / 60)
                sys.settrace(rendered.trace)
                renderer.render(world)
                sys.settrace(None)
        finally:
            sys.settrace(None)
            renderer.destroy()
    by_module: Counter[str] = Counter()
    for counter in (scheduled, rendered):
        for filename, n in counter.by_file.items():
            by_module[_module(filename)] += n
    return {
        "per_frame": (scheduled.total() + rendered.total()) / frames,
        "schedule_per_frame": scheduled.total() / frames,
        "render_per_frame": rendered.total() / frames,
        "by_module": {name: n / frames for name, n in by_module.most_common()},
    }


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    # quick: fewer frames counted, as many before them (steady: submitted again) and the same size
    # (at 160x90 the H200's frames did not settle into that within 300 frames)
    warmup, frames = (300, 5) if args.quick else (args.warmup, args.frames)
    width, height = 640, 360
    progress.total = 1
    with progress.step(f"{args.scene}: {frames} frames counted after {warmup}"):
        results = count(args.scene, width, height, warmup, frames)
    print(
        f"{args.scene}: {results['per_frame']:,.0f} bytecodes a frame (schedule {results['schedule_per_frame']:,.0f}, "
        f"render {results['render_per_frame']:,.0f})"
    )
    for name, n in list(results["by_module"].items())[:12]:
        print(f"{n:9,.0f}  {name}")
    return {
        "benchmark": "bytecodes",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "config": {"scene": args.scene, "width": width, "height": height, "warmup": warmup, "frames": frames},
        "results": results,
    }


def main(argv: list[str] | None = None) -> int:
    return standalone(__doc__, add_arguments, run, argv)


if __name__ == "__main__":
    sys.exit(main())
