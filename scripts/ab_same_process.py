"""Two engines in one process, in alternating blocks of frames: an older tree's copy under another
package name (`--old`) and the installed `ecs_engine`, each drawing its own world into its own
offscreen target.

A small frame's time moves with the host's core speed, which drifts about 2x within minutes on
the GPU host, and two processes run side by side (scripts/device_run.sh abpar) do not see the same
speed either: their loops differed by up to 2x within a pair. Here both engines share the core and
the moment, block by block, so the ratio of their times is the engines' alone. What is timed is a
frame's CPU work: `Schedule.run` and `Renderer.render`, less the time the render waited for a
frame slot's fence (`FrameStats.wait_ms`), as `bench frame` counts it.

The old tree is made importable under another name first, for example:

    pip install --no-deps --target /tmp/old .ab/base
    cp -r /tmp/old/ecs_engine /tmp/renamed/ecs_old
    find /tmp/renamed/ecs_old -name '*.py' -exec sed -i 's/\\becs_engine\\b/ecs_old/g' {} +
    PYTHONPATH=/tmp/renamed:... python3 scripts/ab_same_process.py --old ecs_old --scene cube

It prints one JSON object: per engine ("old", "new") the median frame (ms), the per-block
medians, and the median of the blocks' ratios (new / old).
"""

from __future__ import annotations

import argparse
import importlib
import json
import statistics
import sys
import time
from contextlib import ExitStack
from typing import Any


def _engine(package: str, args: argparse.Namespace, stack: ExitStack) -> Any:
    """A frame function of `package`'s engine drawing `args.scene`: () -> CPU ms of one frame."""
    try:
        scenes = importlib.import_module(f"{package}.app.scenes")
    except ImportError as exc:
        raise SystemExit(f"ab_same_process: cannot import the engine {package!r}: {exc}") from None
    bench = importlib.import_module(f"{package}.bench")
    world_module = importlib.import_module(f"{package}.ecs.world")
    jobs = importlib.import_module(f"{package}.jobs")
    try:
        renderer_class = importlib.import_module(f"{package}.render.frame.renderer").Renderer
    except ImportError:  # trees before the renderer's sub-packages
        renderer_class = importlib.import_module(f"{package}.render.renderer").Renderer
    width, height = (int(v) for v in args.size.split("x"))
    device, target, meshes = stack.enter_context(bench.headless_gpu(width, height))
    pool = stack.enter_context(jobs.JobPool(args.threads)) if args.threads > 1 else None
    world = world_module.World()
    scenes.scene_builder(args.scene, args.entities)(world, meshes.add)
    if pool is not None:
        world.resources[jobs.JobPool] = pool
    schedule = scenes.default_schedule()
    renderer = renderer_class(device, target, meshes, mode=args.mode, culling=args.culling, jobs=pool)
    stack.callback(renderer.destroy)
    clock = time.perf_counter

    def frame() -> float:
        start = clock()
        schedule.run(world, 1 / 60)
        stats = renderer.render(world)
        return (clock() - start) * 1e3 - stats.wait_ms

    return frame


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--old", required=True, help="the older tree's package name (importable)")
    parser.add_argument("--new", default="ecs_engine", help="the newer tree's package name (default ecs_engine)")
    parser.add_argument("--scene", default="cube")
    parser.add_argument("--size", default="640x360")
    parser.add_argument("--entities", type=int, default=10_000, help="the scaling scene's count")
    parser.add_argument("--mode", default="instanced")
    parser.add_argument("--culling", default="frustum")
    parser.add_argument("--threads", type=int, default=1, help="worker threads (a JobPool each, above 1)")
    parser.add_argument("--warmup", type=int, default=300, help="frames each engine draws before the timing")
    parser.add_argument("--blocks", type=int, default=40, help="blocks per engine, alternated")
    parser.add_argument("--block", type=int, default=100, help="frames a block")
    args = parser.parse_args(argv)
    with ExitStack() as stack:
        # by role, so that one package may be both (a smoke test of the harness)
        engines = {"old": _engine(args.old, args, stack), "new": _engine(args.new, args, stack)}
        for frame in engines.values():
            for _ in range(args.warmup):
                frame()
        times: dict[str, list[float]] = {name: [] for name in engines}
        blocks: dict[str, list[float]] = {name: [] for name in engines}
        for b in range(args.blocks):
            order = list(engines) if b % 2 == 0 else list(reversed(engines))  # each goes first half the time
            for name in order:
                frame = engines[name]
                block = [frame() for _ in range(args.block)]
                times[name] += block
                blocks[name].append(statistics.median(block))
    ratios = [n / o for n, o in zip(blocks["new"], blocks["old"], strict=True)]
    print(
        json.dumps(
            {
                "packages": {"old": args.old, "new": args.new},
                "scene": args.scene,
                "size": args.size,
                "mode": args.mode,
                "culling": args.culling,
                "threads": args.threads,
                "entities": args.entities,
                "frames_per_engine": args.blocks * args.block,
                "median_ms": {name: statistics.median(t) for name, t in times.items()},
                "block_medians_ms": blocks,
                "median_block_ratio": statistics.median(ratios),
                "blocks_new_slower": sum(r > 1 for r in ratios),
            }
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
