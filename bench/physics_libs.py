"""Rigid-body libraries on the engine's workloads, before one is chosen (docs/physics.md).

Each library installed in this interpreter runs the same four workloads, all at 60 Hz steps:
- `pile`: N dynamic unit boxes (10,000) in a grid dropped on a static ground: the median ms of a
  step over the first steps, and of reading every body's position and rotation back into NumPy
  (what the engine must do each fixed step to move the Transform columns);
- `statics`: 100,000 static boxes on a floor with 1,000 dynamic spheres falling on them: ms a step;
- `rays`: 10,000 rays cast down onto the settled pile in one go (a batch where the library has
  one, else a loop): ms for all;
- `churn`: 1,000 bodies added then removed at run time: ms for both;
- `deterministic`: two worlds of 1,000 boxes built and stepped alike end with the same poses, bit
  for bit (the library's own threads at work).

Libraries: `rapier3d` (dimforge's own bindings of Rapier), `culverin` (bindings of Jolt Physics
with positions and rotations as shared buffers: CPython 3.12 and newer only), `pybullet`. One
that is not installed is listed as such; the benchmark never fails for it. The pile's sanity:
the boxes' mean height must have dropped and none may be below the floor (a library that lets
them fall through it, or never moves them, is reported as `settled: false`).

JSON (schema_version 1): {"benchmark": "physics-libs", "quick", "machine", "config": {"boxes",
"statics", "movers", "rays", "churn", "steps"}, "libraries": [{"name", "version", "installed",
"threads", "pile": {"step_ms", "readback_ms", "mean_height_before", "mean_height_after",
"lowest_after", "settled"}, "statics": {"step_ms"}, "rays": {"ms", "hits", "batched"}, "churn": {"add_ms",
"remove_ms"}, "deterministic"}]}.
"""

from __future__ import annotations

import argparse
import importlib
import os
import statistics
import time
from typing import Any

import numpy as np

DT = 1.0 / 60.0
THREADS = 0  # the libraries' own defaults (the JSON records each one's)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--boxes", type=int, default=10_000, help="dynamic boxes in the pile (default 10,000)")
    parser.add_argument("--statics", type=int, default=100_000, help="static boxes (default 100,000)")
    parser.add_argument("--steps", type=int, default=120, help="timed steps per workload (default 120)")


def grid(n: int, spacing: float, y0: float) -> np.ndarray:
    """`n` points on a cube-ish grid, `spacing` apart, the lowest layer at height `y0`."""
    side = int(np.ceil(n ** (1 / 3)))
    i = np.arange(n)
    x, y, z = i % side, (i // side) % side, i // (side * side)
    return np.stack([(x - side / 2) * spacing, y0 + y * spacing, (z - side / 2) * spacing], axis=1)


def tiles(n: int) -> np.ndarray:
    """`n` unit boxes' centres side by side in one layer on y = 0.5: a floor of boxes."""
    side = int(np.ceil(np.sqrt(n)))
    i = np.arange(n)
    return np.stack([(i % side) - side / 2, np.full(n, 0.5), (i // side) - side / 2], axis=1)


class Bodies:
    """The dynamic bodies an adapter made, in order (what `poses` reads back)."""

    bodies: list[Any]

    def forget(self, handles: list[Any]) -> None:
        gone = set(handles)
        self.bodies = [h for h in self.bodies if h not in gone]


class Rapier(Bodies):
    name = "rapier3d"

    def __init__(self, lib: Any, capacity: int) -> None:
        self.lib = lib
        self.world = lib.PhysicsWorld(gravity=(0.0, -9.81, 0.0))
        self.world.integration_parameters.dt = DT
        self.bodies: list[Any] = []

    def threads(self) -> int:
        return int(self.world.num_threads)

    def ground(self, half: float) -> None:
        self.world.add_collider(self.lib.Collider.cuboid(half, 0.5, half, translation=(0.0, -0.5, 0.0)))

    def statics(self, points: np.ndarray) -> None:
        for p in points:
            self.world.add_collider(self.lib.Collider.cuboid(0.5, 0.5, 0.5, translation=tuple(p)))

    def dynamic(self, points: np.ndarray, sphere: bool = False) -> list[Any]:
        rp = self.lib
        shape = (lambda: rp.Collider.ball(0.5)) if sphere else (lambda: rp.Collider.cuboid(0.5, 0.5, 0.5))
        made = [self.world.add_body(rp.RigidBody.dynamic(translation=tuple(p)), colliders=[shape()]) for p in points]
        self.bodies += made
        return made

    def remove(self, handles: list[Any]) -> None:
        for h in handles:
            self.world.remove_body(h)
        self.forget(handles)

    def step(self) -> None:
        self.world.step()

    def poses(self) -> tuple[np.ndarray, np.ndarray]:
        """No call returns every pose: one body at a time (what the engine would pay)."""
        n = len(self.bodies)
        pos, rot = np.empty((n, 3)), np.empty((n, 4))
        get = self.world.rigid_bodies.get
        for i, h in enumerate(self.bodies):
            b = get(h)
            t, q = b.translation, b.rotation
            pos[i] = (t.x, t.y, t.z)
            rot[i] = (q.i, q.j, q.k, q.w)
        return pos, rot

    def rays(self, starts: np.ndarray, direction: tuple[float, float, float]) -> tuple[int, bool]:
        cast, ray = self.world.query_pipeline.cast_ray, self.lib.Ray
        return sum(cast(ray(tuple(s), direction), 100.0, True) is not None for s in starts), False


class Culverin(Bodies):
    name = "culverin"

    def __init__(self, lib: Any, capacity: int) -> None:
        self.lib = lib
        pairs = max(65_536, 16 * capacity)  # a settled pile of N boxes keeps ~8N contacts
        settings = {"max_bodies": capacity + 16, "max_pairs": pairs, "max_contact_constraints": pairs}
        settings["temp_allocator_size"] = max(32 << 20, 4096 * capacity)  # the solver's scratch: 40 MB at 10k
        self._threads = settings["num_threads"] = len(os.sched_getaffinity(0))  # as rapier3d's pool (default 4)
        self.world = lib.PhysicsWorld(settings=settings)
        self.bodies: list[int] = []
        self._index: np.ndarray | None = None  # the bodies' dense indices, until bodies come or go

    def threads(self) -> int:
        return self._threads

    def ground(self, half: float) -> None:
        lib = self.lib
        size = (half, 0.5, half)
        self.world.create_body(pos=(0.0, -0.5, 0.0), size=size, shape=lib.SHAPE_BOX, motion=lib.MOTION_STATIC)

    def statics(self, points: np.ndarray) -> None:
        lib, create = self.lib, self.world.create_body
        for p in points:  # (not create_bodies_batch: its bodies collide with nothing, in 0.15.0)
            create(pos=tuple(p), size=(0.5, 0.5, 0.5), shape=lib.SHAPE_BOX, motion=lib.MOTION_STATIC)

    def dynamic(self, points: np.ndarray, sphere: bool = False) -> list[int]:
        lib = self.lib
        shape, size = (lib.SHAPE_SPHERE, 0.5) if sphere else (lib.SHAPE_BOX, (0.5, 0.5, 0.5))
        create = self.world.create_body  # (one call a body: see statics)
        made = [create(pos=tuple(p), size=size, shape=shape, motion=lib.MOTION_DYNAMIC) for p in points]
        self.world.step(0.0)  # creation is deferred: a step of 0 s makes them (and their indices)
        self.bodies += made
        self._index = None
        return made

    def remove(self, handles: list[int]) -> None:
        self.world.destroy_bodies_batch(handles)
        self._index = None
        self.forget(handles)

    def step(self) -> None:
        self.world.step(DT)

    def poses(self) -> tuple[np.ndarray, np.ndarray]:
        """The shared buffers, gathered at the bodies' dense indices (asked again after bodies
        come or go: a removal moves others into its slot)."""
        index = self._index
        if index is None:
            self.world.step(0.0)
            index = self._index = np.array([self.world.get_index(h) for h in self.bodies], np.int64)
        pos = np.frombuffer(self.world.positions, dtype=np.float64).reshape(-1, 4)[index, :3]
        rot = np.frombuffer(self.world.rotations, dtype=np.float32).reshape(-1, 4)[index]
        return pos, rot

    def rays(self, starts: np.ndarray, direction: tuple[float, float, float]) -> tuple[int, bool]:
        dirs = np.tile(np.asarray(direction, np.float32), (len(starts), 1))
        out = self.world.raycast_batch(starts.astype(np.float32).ravel(), dirs.ravel(), 100.0)
        hits = np.frombuffer(out, dtype=np.uint8).reshape(-1, 48)[:, :8].copy().view(np.uint64).ravel()
        return int((hits != 0).sum()), True


class Bullet(Bodies):
    name = "pybullet"

    def __init__(self, lib: Any, capacity: int) -> None:
        self.lib = lib
        self.client = lib.connect(lib.DIRECT)
        lib.setGravity(0, -9.81, 0, physicsClientId=self.client)
        lib.setTimeStep(DT, physicsClientId=self.client)
        self.box = lib.createCollisionShape(lib.GEOM_BOX, halfExtents=[0.5, 0.5, 0.5], physicsClientId=self.client)
        self.ball = lib.createCollisionShape(lib.GEOM_SPHERE, radius=0.5, physicsClientId=self.client)
        self.bodies: list[int] = []

    def threads(self) -> int:
        return 1

    def ground(self, half: float) -> None:
        lib = self.lib
        shape = lib.createCollisionShape(lib.GEOM_BOX, halfExtents=[half, 0.5, half], physicsClientId=self.client)
        lib.createMultiBody(0, shape, basePosition=[0, -0.5, 0], physicsClientId=self.client)

    def statics(self, points: np.ndarray) -> None:
        for p in points:
            self.lib.createMultiBody(0, self.box, basePosition=list(p), physicsClientId=self.client)

    def dynamic(self, points: np.ndarray, sphere: bool = False) -> list[int]:
        shape = self.ball if sphere else self.box
        made = [self.lib.createMultiBody(1.0, shape, basePosition=list(p), physicsClientId=self.client) for p in points]
        self.bodies += made
        return made

    def remove(self, handles: list[int]) -> None:
        for h in handles:
            self.lib.removeBody(h, physicsClientId=self.client)
        self.forget(handles)

    def step(self) -> None:
        self.lib.stepSimulation(physicsClientId=self.client)

    def poses(self) -> tuple[np.ndarray, np.ndarray]:
        n = len(self.bodies)
        pos, rot = np.empty((n, 3)), np.empty((n, 4))
        get = self.lib.getBasePositionAndOrientation
        for i, h in enumerate(self.bodies):
            pos[i], rot[i] = get(h, physicsClientId=self.client)
        return pos, rot

    def rays(self, starts: np.ndarray, direction: tuple[float, float, float]) -> tuple[int, bool]:
        ends = starts + np.asarray(direction) * 100.0
        out = self.lib.rayTestBatch(starts.tolist(), ends.tolist(), physicsClientId=self.client)
        return sum(r[0] >= 0 for r in out), True


ADAPTERS = {"rapier3d": Rapier, "culverin": Culverin, "pybullet": Bullet}


def timed(fn: Any, repeat: int) -> float:
    """The median ms of `repeat` calls of `fn`."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def measure(name: str, lib: Any, config: dict[str, int]) -> dict[str, Any]:
    boxes, steps = config["boxes"], config["steps"]
    make = ADAPTERS[name]
    sim = make(lib, boxes + config["churn"] + 1)
    sim.ground(200.0)
    sim.dynamic(grid(boxes, 1.2, 1.0))
    before = float(sim.poses()[0][:, 1].mean())
    step_ms = timed(sim.step, steps)
    readback_ms = timed(sim.poses, max(3, steps // 10))
    heights = sim.poses()[0][:, 1]
    after, lowest = float(heights.mean()), float(heights.min())
    for _ in range(steps):  # settled enough for the rays to land on boxes
        sim.step()
    starts = grid(config["rays"], 0.5, 60.0)
    starts[:, 1] = 60.0
    t0 = time.perf_counter()
    hits, batched = sim.rays(starts, (0.0, -1.0, 0.0))
    rays_ms = (time.perf_counter() - t0) * 1e3
    t0 = time.perf_counter()
    extra = sim.dynamic(grid(config["churn"], 1.2, 80.0))
    sim.step()
    add_ms = (time.perf_counter() - t0) * 1e3
    t0 = time.perf_counter()
    sim.remove(extra)
    sim.step()
    remove_ms = (time.perf_counter() - t0) * 1e3
    threads = sim.threads()
    del sim
    same = deterministic(make, lib, min(boxes, 1_000), steps)
    floor = make(lib, config["statics"] + config["movers"] + 1)
    floor.statics(tiles(config["statics"]))
    floor.dynamic(grid(config["movers"], 1.5, 3.0), sphere=True)
    statics_ms = timed(floor.step, steps)
    return {
        "threads": threads,
        "pile": {
            "step_ms": step_ms,
            "readback_ms": readback_ms,
            "mean_height_before": before,
            "mean_height_after": after,
            "lowest_after": lowest,
            "settled": bool(after < before - 0.05 and lowest > 0.0),  # fallen, and none through the floor
        },
        "statics": {"step_ms": statics_ms},
        "rays": {"ms": rays_ms, "hits": hits, "batched": batched},
        "churn": {"add_ms": add_ms, "remove_ms": remove_ms},
        "deterministic": same,
    }


def deterministic(make: Any, lib: Any, boxes: int, steps: int) -> bool:
    """Whether two worlds built and stepped alike end with the same poses, bit for bit."""
    ends = []
    for _ in range(2):
        sim = make(lib, boxes + 1)
        sim.ground(200.0)
        sim.dynamic(grid(boxes, 1.2, 1.0))
        for _ in range(steps):
            sim.step()
        pos, rot = sim.poses()
        ends.append((pos.tobytes(), rot.tobytes()))
        del sim
    return ends[0] == ends[1]


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    if args.quick:
        config = {"boxes": 300, "statics": 2_000, "movers": 50, "rays": 300, "churn": 50, "steps": 60}
    else:
        config = {"boxes": args.boxes, "statics": args.statics, "movers": 1_000, "rays": 10_000, "churn": 1_000}
        config["steps"] = args.steps
    libraries = []
    progress.total = len(ADAPTERS)
    for name in ADAPTERS:
        with progress.step(name):
            try:
                lib = importlib.import_module(name)
            except ImportError:
                libraries.append({"name": name, "installed": False})
                continue
            version = getattr(lib, "__version__", None) or _dist_version(name)
            libraries.append({"name": name, "version": version, "installed": True, **measure(name, lib, config)})
    print(table(libraries, config))
    return {
        "benchmark": "physics-libs",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "config": config,
        "libraries": libraries,
    }


def _dist_version(name: str) -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(name)
    except PackageNotFoundError:
        return None


def table(libraries: list[dict[str, Any]], config: dict[str, int]) -> str:
    head = (
        f"{'library':10} {'pile step ms':>12} {'read-back ms':>12} {'settled':>7} {'statics step ms':>15} "
        f"{'rays ms':>8} {'add ms':>7} {'remove ms':>9} {'same twice':>10}"
    )
    sizes = f"{config['boxes']:,} boxes, {config['statics']:,} statics + {config['movers']:,} movers"
    rows = [f"{sizes}, {config['rays']:,} rays", head]
    for r in libraries:
        if not r["installed"]:
            rows.append(f"{r['name']:10} not installed")
            continue
        p = r["pile"]
        rows.append(
            f"{r['name']:10} {p['step_ms']:12.2f} {p['readback_ms']:12.3f} {p['settled']!s:>7} "
            f"{r['statics']['step_ms']:15.2f} {r['rays']['ms']:8.2f} {r['churn']['add_ms']:7.1f} "
            f"{r['churn']['remove_ms']:9.1f} {r['deterministic']!s:>10}"
        )
    return "\n".join(rows)
