"""The PhysicsWorld resource: the library's world, the bodies made from the ECS's RigidBody and
Collider components, and the bulk moves between them (see PhysicsSystem in plugin.py)."""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..components.physics import PRIMITIVES, STATIC
from ..ecs.entities import INDEX_MASK
from . import queries, ray_grid
from .bodies import Bodies
from .characters import Characters
from .contacts import record_dtype
from .library import load
from .poses import copy_poses, copy_vectors
from .queries import RayHits, ShapeHit
from .ray_grid import RayGrid, Shapes

# what becomes events: nothing; Trigger events only (the default: read only while a sensor exists);
# Contact events too for bodies beginning and ending to touch; or every touching pair every step
# too (STAY: some 8 rows a body in a pile). Contacts are asked for, as avian's and bevy_rapier's
# are: reading the library's records copies its buffer, which holds every touching pair up to
# about 10,000 records a step (measured): ~1 ms a step in a pile of 10,000 boxes, all of it
# pairs that went on touching, so that beginnings past the cap are lost
CONTACTS = ("none", "triggers", "begin_end", "all")


class PhysicsWorld:
    """The world's physics: `gravity` (m/s^2, a vector), the library's worker `threads` (None: one
    per core) and the most bodies it holds (`max_bodies`). The bodies are the entities with
    Transform, RigidBody and Collider; PhysicsSystem makes and destroys them as those come and go,
    steps the world once per fixed step and writes the dynamic bodies' poses back in bulk.
    `contacts`: which touches become events (CONTACTS: Trigger events only, by default).
    `native` is the library's world (culverin's PhysicsWorld) for what the engine does not wrap."""

    def __init__(
        self,
        gravity: tuple[float, float, float] = (0.0, -9.81, 0.0),
        threads: int | None = None,
        max_bodies: int = 65_536,
        contacts: str = "triggers",
    ) -> None:
        if contacts not in CONTACTS:
            raise ValueError(f"PhysicsWorld.contacts must be one of {', '.join(CONTACTS)}, got {contacts!r}")
        g = tuple(float(x) for x in gravity)
        if len(g) != 3 or not all(math.isfinite(x) for x in g):
            raise ValueError(f"PhysicsWorld.gravity must be 3 finite numbers, got {gravity!r}")
        if threads is not None and threads < 1:
            raise ValueError(f"PhysicsWorld.threads must be at least 1 (or None: one per core), got {threads}")
        if max_bodies < 1:
            raise ValueError(f"PhysicsWorld.max_bodies must be at least 1, got {max_bodies}")
        self.gravity = g
        self.threads = threads if threads is not None else len(os.sched_getaffinity(0))
        self.max_bodies = int(max_bodies)
        self.lib = load()  # UsageError naming the extra when the library is missing
        pairs = max(65_536, 16 * self.max_bodies)  # a settled pile of N boxes keeps about 8N contacts
        settings = {"gravity": g, "max_bodies": self.max_bodies, "max_pairs": pairs, "max_contact_constraints": pairs}
        settings["temp_allocator_size"] = max(32 << 20, 4096 * self.max_bodies)  # the solver's scratch
        settings["num_threads"] = self.threads
        self.native = self.lib.PhysicsWorld(settings=settings)
        self.bodies = Bodies(self.lib, self.native)
        self.characters = Characters(self.native)
        self._seen = -1  # the world's structure version last matched
        self.contacts = contacts
        self.contact_dtype = record_dtype(bool(self.lib.USE_DOUBLE_PRECISION))
        self.pool: Any = None  # the world's JobPool (PhysicsSystem sets it): how many threads raycast takes
        self.paused = False  # PhysicsSystem does nothing (the editor's Physics window sets it)
        self.step_once = False  # paused: the next fixed step runs once all the same
        self.steps = 0
        self.placed = 0  # times bodies were put where their Transform says (place)
        self._shapes: tuple = ((), None, False)  # ((generation, motions), Shapes, whether other shapes have bodies)
        self._grid: tuple = ((), None)  # (key, RayGrid)
        self.grids_made = 0  # how many times raycast's grid was made (a count for benchmarks)
        self.ray_lock = threading.RLock()  # one batch of rays at a time: a refresh changes the grid in place
        self.step_ms = 0.0  # the library's last step
        self.events_ms = 0.0  # the last step's contact records read and sent as events
        self.events_copy_ms = 0.0  # of which the library's copy of its buffer of records

    def sync(self, world: Any) -> bool:
        """The bodies and characters matched against the world's entities (Bodies.sync): whether
        any body was made or destroyed (then the bodies' rows in the buffers moved)."""
        if world.structure_version == self._seen:
            return False
        self._seen = world.structure_version
        changed = self.bodies.sync(world)
        self.characters.sync(world)
        return changed

    # ------------------------------------------------------------------ the step
    def step(self, dt: float) -> None:
        """One step of the library's world (`step_ms`: what it took, the library's own time)."""
        start = time.perf_counter()
        self.native.step(float(dt))
        self.step_ms = (time.perf_counter() - start) * 1e3
        self.steps += 1

    def rows(self, entities: np.ndarray) -> np.ndarray:
        """The rows of `entities`' bodies in the library's shared buffers (valid until `generation`
        changes: bodies.generation)."""
        return self.bodies.row[entities & INDEX_MASK]

    def buffers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The library's shared buffers, by body row: positions (M, 4) float64, rotations
        (x, y, z, w) float32, linear and angular velocities (M, 4) float32 (read-only views)."""
        native = self.native
        rates = (_view(native.velocities, np.float32), _view(native.angular_velocities, np.float32))
        return (*self.pose_buffers(), *rates)

    def pose_buffers(self) -> tuple[np.ndarray, np.ndarray]:
        """The positions and rotations of `buffers` alone (each view costs: rays ask for them
        each step)."""
        return _view(self.native.positions, np.float64), _view(self.native.rotations, np.float32)

    def poses(self, entities: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The positions (float64) and unit rotations (x, y, z, w) of `entities`' bodies."""
        return self._poses_at(self.rows(entities))

    def _poses_at(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The poses of the bodies at `rows`, as write_poses puts them into Transform."""
        position, rotation = np.empty((len(rows), 3)), np.empty((len(rows), 4))
        self.write_poses(rows, np.arange(len(rows)), position, rotation)
        return position, rotation

    def write_poses(self, rows: np.ndarray, into: np.ndarray, position: np.ndarray, rotation: np.ndarray) -> None:
        """position[into], rotation[into] = the poses of the bodies at `rows` (poses.py)."""
        positions, rotations = self.pose_buffers()
        copy_poses(positions, rotations, rows, into, position, rotation)

    def write_velocities(
        self, rows: np.ndarray, into: np.ndarray, linear: np.ndarray | None, angular: np.ndarray | None
    ) -> None:
        """linear[into], angular[into] = the velocities of the bodies at `rows` (None: not asked)."""
        _, _, lin, ang = self.buffers()
        if linear is not None:
            copy_vectors(lin, rows, into, linear)
        if angular is not None:
            copy_vectors(ang, rows, into, angular)

    def place(self, entities: np.ndarray, transform: Any, rows: np.ndarray) -> None:
        """Move `entities`' (kinematic) bodies to their Transform (`transform`'s `rows`)."""
        put, handles = self.native.set_transform, self.bodies.handle[entities & INDEX_MASK].tolist()
        self.placed += len(handles) > 0
        for h, p, q in zip(handles, transform.position[rows].tolist(), transform.rotation[rows].tolist()):
            put(h, tuple(p), tuple(q))

    def follow_moved(self, rows: np.ndarray, entities: np.ndarray, transform: Any, into: np.ndarray) -> None:
        """Bodies (at `rows`, of `entities`) whose Transform (`transform`'s rows `into`) a system
        changed since the last step wrote it are put there (teleported, their velocity kept). The
        poses are compared as write_poses made them, so an unmoved body compares equal."""
        were, was = self._poses_at(rows)
        moved = np.any(transform.position[into] != were, axis=1) | np.any(transform.rotation[into] != was, axis=1)
        self.place(entities[moved], transform, into[moved])

    def tune(
        self,
        rows: np.ndarray,
        handles: np.ndarray,
        mass: np.ndarray,
        scale: np.ndarray,
        linear: np.ndarray,
        angular: np.ndarray,
        dt: float,
    ) -> None:
        """Before a step: bodies' own gravity scale (a force of (scale - 1) m g) and damping (each
        velocity times 1 - damping dt), which the library has not per body; a call a body."""
        _, _, lin, ang = self.buffers()
        g = np.asarray(self.gravity)
        for k, h in enumerate(handles.tolist()):
            if scale[k] != 1.0:
                self.native.apply_force(h, *((scale[k] - 1.0) * mass[k] * g).tolist())
            if linear[k] > 0.0:
                self.native.set_linear_velocity(h, *(lin[rows[k], :3] * max(0.0, 1.0 - linear[k] * dt)).tolist())
            if angular[k] > 0.0:
                self.native.set_angular_velocity(h, *(ang[rows[k], :3] * max(0.0, 1.0 - angular[k] * dt)).tolist())

    def last_velocity(self, entities: np.ndarray, angular: bool = False) -> np.ndarray:
        """The linear (or `angular`) velocity last written into, or taken from, the Velocity (or
        AngularVelocity) of `entities`."""
        return (self.bodies.angular if angular else self.bodies.velocity)[entities & INDEX_MASK]

    def wrote_velocity(self, entities: np.ndarray, values: np.ndarray, angular: bool = False) -> None:
        (self.bodies.angular if angular else self.bodies.velocity)[entities & INDEX_MASK] = values

    def set_velocity(self, entity: int, value: Any, angular: bool = False) -> None:
        """Give `entity`'s body this linear velocity (m/s), or with `angular` this angular one
        (axis times rad/s), now."""
        handle = self.bodies.handle_of(entity)
        if handle is None:
            raise ValueError(f"entity {entity} has no body")
        v = [float(x) for x in value]
        (self.native.set_angular_velocity if angular else self.native.set_linear_velocity)(handle, *v)
        self.wrote_velocity(np.array([entity]), np.array(v), angular)

    # ------------------------------------------------------------------ queries (queries.py)
    def raycast(self, origins: Any, directions: Any, max_distance: float = 1000.0) -> RayHits:
        """Cast every ray (rows of `origins` and `directions`, which need not be unit length): the
        first body each one hits within `max_distance`. With the world's JobPool (`pool`, which
        PhysicsSystem sets) many rays are cast on as many of numba's threads (ray_spread.py),
        and the library's batch spreads over the pool.
        The engine casts against boxes, spheres, capsules and cylinders (ray_grid.py), the
        library against meshes, hulls and terrain."""
        return queries.raycast(self, origins, directions, max_distance)

    def ray_grid(self, refresh: Callable[[RayGrid, bool], bool] | None = None) -> tuple[RayGrid | None, bool]:
        """The grid raycast casts against (None without numba), brought up to the step after a
        step or a body placed (RayGrid.refresh), made again when a body was made or destroyed
        or the refresh could not keep it; and whether bodies of other shapes than the
        primitives (meshes, hulls, terrain) are there, for the library to cast against. Hold
        `ray_lock` while the grid is in use: a refresh changes it in place. `refresh(grid,
        everything)`: what brings the grid up instead of RayGrid.refresh (raycast's casts the
        rays in the same kernel), False where it could not."""
        with self.ray_lock:
            bodies = self.bodies
            if self._shapes[0] != (bodies.generation, bodies.motions):
                slots = np.flatnonzero(bodies.owner >= 0)
                primitive = np.isin(bodies.spec["shape"][slots], PRIMITIVES)
                at = slots[primitive]
                spec, still = bodies.spec[at], bodies.kind[at] == STATIC
                shapes = Shapes.of(bodies.owner[at], bodies.row[at], spec["shape"], spec["size"], still)
                self._shapes = ((bodies.generation, bodies.motions), shapes, not primitive.all())
            key = (bodies.generation, self.steps, self.placed)
            if ray_grid.AVAILABLE and key != self._grid[0]:
                positions, rotations = self.pose_buffers()
                grid, everything = self._grid[1], self._grid[0][2:] != (self.placed,)
                bring = RayGrid.refresh if refresh is None else refresh
                if grid is None or not (grid.serves(self._shapes[1], positions, rotations) and bring(grid, everything)):
                    grid = RayGrid.build(self._shapes[1], positions, rotations, self.pool)
                    self.grids_made += 1
                self._grid = (key, grid)
            return self._grid[1], self._shapes[2]

    def shapecast(
        self, shape: int, size: Any, origin: Any, motion: Any, rotation: Any = (0.0, 0.0, 0.0, 1.0), ignore: int = -1
    ) -> ShapeHit | None:
        """Sweep a `shape` (BOX, SPHERE, CAPSULE, CYLINDER, sized as a Collider's) from `origin`
        along `motion` (a vector: where it would end), turned by `rotation`: the first body it
        touches (not `ignore`'s), or None."""
        return queries.shapecast(self, shape, size, origin, motion, rotation, ignore)

    def overlap_sphere(self, centre: Any, radius: float) -> np.ndarray:
        """The entities whose bodies overlap a sphere (their exact shapes, not their bounds)."""
        return queries.overlap_sphere(self, centre, radius)

    def overlap_box(self, low: Any, high: Any) -> np.ndarray:
        """The entities whose bodies' bounds overlap the axis-aligned box from `low` to `high`."""
        return queries.overlap_box(self, low, high)


def _view(buffer: Any, dtype: Any) -> np.ndarray:
    """A read-only (M, 4) view of one of the library's buffers."""
    view = np.frombuffer(buffer, dtype).reshape(-1, 4)
    view.flags.writeable = False
    return view
