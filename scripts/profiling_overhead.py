"""What per-system timing costs the schedule: the stock schedule (app/scenes.py) over the 1-cube
demo's world (its cube, camera and six orbiting lights; no GPU: meshes are not uploaded), run
many times, untimed (the default: Schedule.timer None) and timed (the app's Profiler, as while
the Perf window is drawn or a trace is recorded). A micro benchmark, not a test: the figures
vary with the machine; docs/performance.md ("Profiling") has what it gave.

    python scripts/profiling_overhead.py [--frames 1000] [--repeats 30]
"""

from __future__ import annotations

import argparse
import time

from ecs_engine.app.scenes import default_schedule, scene_builder
from ecs_engine.ecs import World


def frame_us(timed: bool, frames: int, repeats: int) -> float:
    """The least over `repeats` of the mean schedule run (us), the world as the 1-cube demo's:
    the least, as timeit advises, since other processes only ever add time."""
    world = World()
    scene_builder("cube")(world, lambda mesh: 0)
    schedule = default_schedule()
    end_frame = None
    if timed:
        from ecs_engine.app.profiling import Profiler

        profiler = Profiler(always=True)
        profiler.on = True
        schedule.timer = profiler
        end_frame = profiler.end_frame
    results = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for k in range(frames):
            schedule.run(world, 1 / 60)
            if end_frame is not None:
                end_frame(k, 0, 0, None)
        results.append((time.perf_counter() - t0) / frames * 1e6)
    return min(results)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=30)
    parser.add_argument("--untimed-only", action="store_true", help="for code without the timing hooks")
    args = parser.parse_args()
    frame_us(False, 500, 1)  # numba compiles and first-call costs out of the figures
    print(f"untimed: {frame_us(False, args.frames, args.repeats):.2f} us a frame")
    if not args.untimed_only:
        print(f"timed:   {frame_us(True, args.frames, args.repeats):.2f} us a frame")


if __name__ == "__main__":
    main()
