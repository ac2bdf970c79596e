"""Old code against new on the frames that matter: one process per (code, repetition), alternated,
so the GPU host's drift (30-50% between runs) hits both alike.

Each process builds the seed's three scenes and the scaling scene (bench/scaling.py's) at 100 and
1,000,000 entities, headless (640x360, or the size given as a third argument), and prints one
JSON line per configuration: the median over its timed frames of systems ms, record ms, CPU
frame ms (systems + render, minus waits for the GPU) and GPU ms (timestamps, a frame late). It
runs against the API of the code it finds, old (before the issue-13 refactor, commit f7a779d) or
new (issue 14 compared e7d674c, before materials, with the materials code).

    pip install --no-deps --no-build-isolation --target /tmp/old <old checkout>
    pip install --no-deps --no-build-isolation --target /tmp/new .
    cd /tmp && for rep in 1 2 3; do for v in new old; do
        PYTHONPATH=/tmp/$v python3 /path/to/ab_frames.py $v $rep >> ab.jsonl; done; done

(a fourth argument `small` leaves out the 1M-entity frames).

(alternate which one goes first between repetitions). Results of one such run:
bench/results/runs/ab-13/frames-h100-16c.json.
"""

from __future__ import annotations

import json
import statistics
import sys
import time
from typing import Any

# (scene, entities, mode, threads, timed frames, warm-up frames)
CONFIGS = [
    ("cube", 1, "instanced", 1, 300, 50),
    ("grid100", 100, "instanced", 1, 300, 50),
    ("model", 1, "instanced", 1, 300, 50),
    ("scaling", 100, "instanced", 1, 300, 50),
    ("scaling", 1_000_000, "instanced", 16, 40, 8),
    ("scaling", 1_000_000, "indirect", 16, 40, 8),
    ("scaling", 1_000_000, "instanced", 1, 16, 4),
]


def engine_api() -> tuple[Any, ...]:
    """The names this script needs, from the new layout or the old flat one."""
    try:
        from ecs_engine.app.scenes import default_schedule, scene_builder
        from ecs_engine.ecs.world import World
        from ecs_engine.render.assets.mesh_registry import MeshRegistry
        from ecs_engine.render.frame.renderer import Renderer

        return default_schedule, scene_builder, MeshRegistry, Renderer, World, {}
    except ImportError:
        pass
    try:  # render/ before its sub-packages (issue 36)
        from ecs_engine.app.scenes import default_schedule, scene_builder
        from ecs_engine.ecs.world import World
        from ecs_engine.render.mesh_registry import MeshRegistry
        from ecs_engine.render.renderer import Renderer

        return default_schedule, scene_builder, MeshRegistry, Renderer, World, {}
    except ImportError:
        from ecs_engine.app import default_schedule, scene_builder  # type: ignore[attr-defined]
        from ecs_engine.mesh_registry import MeshRegistry  # type: ignore[import-not-found]
        from ecs_engine.renderer import Renderer  # type: ignore[import-not-found]
        from ecs_engine.world import World  # type: ignore[import-not-found]

        return default_schedule, scene_builder, MeshRegistry, Renderer, World, {"lights": True}


def main() -> None:
    version, rep = sys.argv[1], int(sys.argv[2])
    width, height = (int(v) for v in (sys.argv[3] if len(sys.argv) > 3 else "640x360").split("x"))
    default_schedule, scene_builder, MeshRegistry, Renderer, World, extra = engine_api()
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance
    from ecs_engine.gpu.offscreen import OffscreenTarget
    from ecs_engine.jobs import JobPool

    instance = Instance()
    device = Device(instance)
    target = OffscreenTarget(device, width, height)
    meshes = MeshRegistry(device)
    worlds: dict[tuple[str, int], Any] = {}
    small = len(sys.argv) > 4 and sys.argv[4] == "small"  # the seed scenes only (no 1M frames)
    for scene, n, mode, threads, frames, warmup in CONFIGS:
        if small and n > 100:
            continue
        pool = JobPool(threads)
        if (scene, n) not in worlds:
            worlds[scene, n] = World()
            scene_builder(scene, n)(worlds[scene, n], meshes.add)
        world = worlds[scene, n]
        world.resources[JobPool] = pool
        renderer = Renderer(device, target, meshes, mode=mode, jobs=pool, **extra)
        schedule = default_schedule()
        systems, record, cpu, gpu = [], [], [], []
        for i in range(warmup + frames):
            t0 = time.perf_counter()
            schedule.run(world, 1 / 60)
            t1 = time.perf_counter()
            stats = renderer.render(world)
            t2 = time.perf_counter()
            if i >= warmup:
                systems.append((t1 - t0) * 1e3)
                record.append(stats.record_ms)
                cpu.append((t2 - t0) * 1e3 - stats.wait_ms)
                if stats.gpu_ms is not None:
                    gpu.append(stats.gpu_ms)
        device.wait_idle()
        renderer.destroy()
        pool.close()
        row = {
            "version": version,
            "rep": rep,
            "scene": scene,
            "size": f"{width}x{height}",
            "entities": n,
            "mode": mode,
            "threads": threads,
            "systems_ms": statistics.median(systems),
            "record_ms": statistics.median(record),
            "cpu_ms": statistics.median(cpu),
            "gpu_ms": statistics.median(gpu) if gpu else None,
        }
        print(json.dumps(row), flush=True)
    meshes.destroy()
    target.destroy()
    device.destroy()
    instance.destroy()


if __name__ == "__main__":
    main()
