"""Physics through the engine (ecs_engine.physics on culverin/Jolt): what the engine adds to the
library's own step, at the workloads of docs/physics.md.

- `pile`: N dynamic unit boxes (10,000) spawned in one batch over a static floor, stepped by
  PhysicsSystem in a one-stage schedule: per step, the library's own step (PhysicsWorld.step_ms)
  and the whole system's run (the schedule's, timed around it); the engine's added time is their
  difference: making no body (the world's structure stands), the velocities compared, the poses
  and velocities gathered into Transform and Velocity, the contact records read and sent as
  Contact events (asked for: `contacts="begin_end"`; `events_ms`, of which `events_copy_ms` is
  the library's copy of its buffer of records, which the engine must ask for; also taken out:
  `added_without_events`, the default's cost without sensors). Target: at most 10% of the
  library's step.
  Also the first step's cost of making every body (`create_ms`).
- `statics`: 100,000 static boxes and 1,000 dynamic spheres falling on them, likewise; and
  the same 10,000 rays onto them (`statics_rays`: the refresh of the grid looks at the moving
  shapes only).
- `rays`: 10,000 rays cast down onto the settled pile through PhysicsWorld.raycast (with a
  JobPool of the threads: on as many of numba's threads, which take blocks of rays as they come
  free; answered as entities),
  once a step for 30 steps (`ms`: the median step, `mean_ms`, `max_ms`; the grid of the shapes
  is made again `remade` times, when too many shapes found no room in its cells; `grid_ms`:
  making it alone). Target: under 1 ms. Beside it, the library's own batch on the same rays
  (`library_ms`) and the share of rays both answer alike (`same_as_library`).

JSON (schema_version 1): {"benchmark": "physics", "quick", "machine", "library": {"name",
"version"}, "config": {"boxes", "statics", "movers", "rays", "steps", "threads"}, "pile":
{"create_ms", "library_step_ms", "system_step_ms", "added_ms", "added_fraction", "events_ms",
"events_copy_ms", "added_without_events_ms", "added_without_events_fraction", "settled"},
"statics": {same but settled}, "rays": {"ms", "first_ms", "mean_ms", "max_ms", "remade", "steps",
"grid_ms", "library_ms", "hits", "same_as_library", "python_loop_ns": the core's speed before and
after}, "statics_rays": {same as rays}, "targets": {"added_fraction_max",
"rays_ms_max", "added_met", "added_without_events_met", "rays_met"}}; medians over the timed steps.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from typing import Any

import numpy as np

from .machine import python_loop_ns
from .physics_libs import grid, tiles

DT = 1.0 / 60.0
ADDED_MAX = 0.10  # the engine may add at most 10% to the library's step at 10,000 bodies
RAYS_MS_MAX = 1.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--boxes", type=int, default=10_000, help="dynamic boxes in the pile (default 10,000)")
    parser.add_argument("--statics", type=int, default=100_000, help="static boxes (default 100,000)")
    parser.add_argument("--steps", type=int, default=120, help="timed steps per workload (default 120)")
    parser.add_argument("--threads", type=int, default=None, help="the library's threads (default: one per core)")


def preflight(args: argparse.Namespace) -> None:
    from ecs_engine.errors import UsageError
    from ecs_engine.physics.library import load

    if min(args.boxes, args.statics, args.steps) < 1 or (args.threads is not None and args.threads < 1):
        raise UsageError("--boxes, --statics, --steps and --threads must be at least 1")
    load()  # UsageError naming the extra


def workload(statics: np.ndarray | None, dynamic: np.ndarray, sphere: bool, steps: int, threads: int) -> dict:
    """A world of a floor (or `statics` boxes) and `dynamic` bodies stepped `steps` times."""
    from ecs_engine.components import Transform
    from ecs_engine.components.physics import BOX, SPHERE, STATIC, Collider, RigidBody
    from ecs_engine.ecs.schedule import Schedule
    from ecs_engine.ecs.world import World
    from ecs_engine.physics import PhysicsSystem, PhysicsWorld

    count = len(dynamic) + (len(statics) if statics is not None else 1)
    world = World()
    physics = world.resources[PhysicsWorld] = PhysicsWorld(threads=threads, max_bodies=count + 16, contacts="begin_end")
    if statics is None:
        world.spawn(Transform(position=(0.0, -0.5, 0.0)), RigidBody(kind=STATIC), Collider(size=(400.0, 0.5, 400.0)))
    else:
        world.spawn_batch(len(statics), Transform(position=statics), RigidBody(kind=STATIC), Collider(shape=BOX))
    shape = SPHERE if sphere else BOX
    moving = world.spawn_batch(len(dynamic), Transform(position=dynamic), RigidBody(), Collider(shape=shape))
    schedule = Schedule(("fixed",))
    schedule.add(PhysicsSystem(), "fixed")
    start = time.perf_counter()
    schedule.run(world, DT)  # makes every body, then the first step
    create_ms = (time.perf_counter() - start) * 1e3 - physics.step_ms
    library, system, events, copies = [], [], [], []
    for _ in range(steps):
        start = time.perf_counter()
        schedule.run(world, DT)
        system.append((time.perf_counter() - start) * 1e3)
        library.append(physics.step_ms)
        events.append(physics.events_ms)
        copies.append(physics.events_copy_ms)
    heights = physics.poses(moving)[0][:, 1]
    lib_ms, sys_ms = statistics.median(library), statistics.median(system)
    added = statistics.median(s - lib for s, lib in zip(system, library))
    bare = statistics.median(s - lib - ev for s, lib, ev in zip(system, library, events))
    result = {
        "create_ms": create_ms,
        "library_step_ms": lib_ms,
        "system_step_ms": sys_ms,
        "added_ms": added,
        "added_fraction": added / lib_ms,
        "events_ms": statistics.median(events),  # of added: the contact records read, sent as events
        "events_copy_ms": statistics.median(copies),  # of those: the library's copy of its buffer
        "added_without_events_ms": bare,
        "added_without_events_fraction": bare / lib_ms,
        "lowest": float(heights.min()),  # of the moving bodies' centres
    }
    return {"world": world, "physics": physics, "result": result}


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    from importlib.metadata import version

    threads = args.threads or len(os.sched_getaffinity(0))
    if args.quick:
        config = {"boxes": 300, "statics": 2_000, "movers": 50, "rays": 300, "steps": 30}
    else:
        config = {"boxes": args.boxes, "statics": args.statics, "movers": 1_000, "rays": 10_000, "steps": args.steps}
    config["threads"] = threads
    machine = {**machine, "threads": threads}  # the library's threads and the ray batches' pool
    progress.total = 3
    with progress.step("pile"):
        pile = workload(None, grid(config["boxes"], 1.2, 1.0), False, config["steps"], threads)
        p = pile["result"]
        p["settled"] = bool(p.pop("lowest") > 0.0)  # none fell through the floor (its top: y = 0)
    with progress.step("rays"):
        physics = pile["physics"]
        for _ in range(config["steps"]):  # the pile settles further before the rays
            physics.step(DT)
        rays = timed_rays(physics, config["rays"], threads)
        del pile, physics
    with progress.step("statics"):
        floor = workload(tiles(config["statics"]), grid(config["movers"], 1.5, 3.0), True, config["steps"], threads)
        statics = floor["result"]
        statics["settled"] = bool(statics.pop("lowest") > 1.0)  # on the statics (their top: y = 1)
        statics_rays = timed_rays(floor["physics"], config["rays"], threads)
        del floor
    targets = {
        "added_fraction_max": ADDED_MAX,
        "rays_ms_max": RAYS_MS_MAX,
        "added_met": p["added_fraction"] <= ADDED_MAX,
        "added_without_events_met": p["added_without_events_fraction"] <= ADDED_MAX,
        "rays_met": rays["ms"] < RAYS_MS_MAX,
    }
    print(table(config, p, statics, rays, targets))
    print(f"on the statics: {rays_line(config, statics_rays)}")
    return {
        "benchmark": "physics",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "library": {"name": "culverin", "version": version("culverin")},
        "config": config,
        "pile": p,
        "statics": statics,
        "rays": rays,
        "statics_rays": statics_rays,
        "targets": targets,
    }


def timed_rays(physics: Any, count: int, threads: int) -> dict:
    """`count` rays cast straight down from y = 60 on a 0.5 m grid, once a step (cast_rays),
    over a JobPool of `threads` as a game's world has; the host's core speed beside."""
    from ecs_engine.jobs import JobPool

    physics.pool = JobPool(threads)
    starts = grid(count, 0.5, 60.0)
    starts[:, 1] = 60.0
    down = np.tile((0.0, -1.0, 0.0), (len(starts), 1))
    before = python_loop_ns()
    rays = cast_rays(physics, starts, down)
    rays["python_loop_ns"] = [before, python_loop_ns()]  # the host's core speed, before and after
    physics.pool.close()
    return rays


def cast_rays(physics: Any, starts: np.ndarray, down: np.ndarray, times: int = 30) -> dict:
    """The rays cast once a step, as a game casts them each frame, `times` steps: the grid of
    the shapes is brought up to each step, and made again only when too many shapes found no
    room in its cells (`remade`: in how many of the steps). `ms` is the median step's cost, `max_ms` the
    worst (a step that made the grid), `mean_ms` the mean; `grid_ms` the grid made alone;
    `first_ms` the first call, before them, which compiles the kernels (or loads them).
    Beside them, the library's own batch on the same rays."""
    from ecs_engine.physics.queries import _library_rays
    from ecs_engine.physics.ray_grid import RayGrid

    start = time.perf_counter()
    physics.raycast(starts, down, 100.0)  # (the first calls compile the kernels, or load them:
    first = (time.perf_counter() - start) * 1e3
    physics.step(DT)
    physics.raycast(starts, down, 100.0)  # the grid made, then the grid looked at again)
    ours, theirs, remade = [], [], 0
    for _ in range(times):
        physics.step(DT)
        before = physics.grids_made
        start = time.perf_counter()
        hits = physics.raycast(starts, down, 100.0)
        ours.append((time.perf_counter() - start) * 1e3)
        remade += physics.grids_made != before
        start = time.perf_counter()
        entity = _library_rays(physics, starts, down, 100.0).entity
        theirs.append((time.perf_counter() - start) * 1e3)
    positions, rotations, _, _ = physics.buffers()
    start = time.perf_counter()
    RayGrid.build(physics.ray_grid()[0].shapes, positions, rotations, physics.pool)
    made = (time.perf_counter() - start) * 1e3
    return {
        "ms": statistics.median(ours),
        "first_ms": first,
        "mean_ms": statistics.fmean(ours),
        "max_ms": max(ours),
        "remade": remade,
        "steps": times,
        "grid_ms": made,
        "library_ms": statistics.median(theirs),
        "hits": int((hits.entity >= 0).sum()),
        "same_as_library": float((hits.entity == entity).mean()),
    }


def rays_line(config: dict, rays: dict) -> str:
    return (
        f"{config['rays']:,} rays a step: median {rays['ms']:.2f} ms, mean {rays['mean_ms']:.2f}, worst "
        f"{rays['max_ms']:.2f} (the grid made again in {rays['remade']} of {rays['steps']} steps, "
        f"{rays['grid_ms']:.2f} ms alone); the library's batch {rays['library_ms']:.2f} ms; "
        f"{rays['hits']:,} hits, {100 * rays['same_as_library']:.1f}% the same"
    )


def table(config: dict, pile: dict, statics: dict, rays: dict, targets: dict) -> str:
    def row(name: str, r: dict) -> str:
        return (
            f"{name:8} {r['create_ms']:10.1f} {r['library_step_ms']:11.2f} {r['system_step_ms']:11.2f} "
            f"{r['added_ms']:9.3f} {100 * r['added_fraction']:7.1f}% {r['events_ms']:10.3f} "
            f"{100 * r['added_without_events_fraction']:14.1f}%"
        )

    met = {True: "MET", False: "MISS"}
    return "\n".join(
        [
            f"{config['boxes']:,} boxes; {config['statics']:,} statics + {config['movers']:,} movers; "
            f"{config['threads']} threads",
            f"{'':8} {'create ms':>10} {'library ms':>11} {'system ms':>11} {'added ms':>9} {'added':>8} "
            f"{'events ms':>10} {'without events':>15}",
            row("pile", pile),
            row("statics", statics),
            rays_line(config, rays),
            f"target {met[targets['added_met']]}: the engine adds <= {ADDED_MAX:.0%} to the pile's step "
            f"({met[targets['added_without_events_met']]} without the contact events)",
            f"target {met[targets['rays_met']]}: {config['rays']:,} rays < {RAYS_MS_MAX} ms",
        ]
    )
