"""The PhysicsWorld resource: the library's world, the bodies made from the ECS's RigidBody and
Collider components, and the bulk moves between them (see PhysicsSystem in plugin.py)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..components import Transform, Velocity
from ..components.physics import BOX, CAPSULE, CYLINDER, DYNAMIC, KINEMATIC, SPHERE, STATIC, Collider, RigidBody
from ..ecs.entities import INDEX_MASK
from .library import load

_MOTIONS = {DYNAMIC: "MOTION_DYNAMIC", KINEMATIC: "MOTION_KINEMATIC", STATIC: "MOTION_STATIC"}
_SHAPES = {BOX: "SHAPE_BOX", SPHERE: "SHAPE_SPHERE", CAPSULE: "SHAPE_CAPSULE", CYLINDER: "SHAPE_CYLINDER"}
# a ray hit as the library packs it (48 bytes)
_HIT = np.dtype(
    [
        ("handle", np.uint64),
        ("fraction", np.float32),
        ("normal", np.float32, 3),
        ("point", np.float32, 3),
        ("sub_shape", np.uint32),
        ("material", np.uint32),
        ("pad", np.uint32),
    ]
)


@dataclass(frozen=True)
class RayHits:
    """Per ray: the `entity` hit first (-1: none), the `distance` along the ray, the hit `point`
    and the surface `normal` there (NaN where nothing was hit)."""

    entity: np.ndarray
    distance: np.ndarray
    point: np.ndarray
    normal: np.ndarray


class PhysicsWorld:
    """The world's physics: `gravity` (m/s^2, a vector), the library's worker `threads` (None: one
    per core) and the most bodies it holds (`max_bodies`). The bodies are the entities with
    Transform, RigidBody and Collider; PhysicsSystem makes and destroys them as those come and go,
    steps the world once per fixed step and writes the dynamic bodies' poses back in bulk.
    `native` is the library's world (culverin's PhysicsWorld) for what the engine does not wrap."""

    def __init__(
        self,
        gravity: tuple[float, float, float] = (0.0, -9.81, 0.0),
        threads: int | None = None,
        max_bodies: int = 65_536,
    ) -> None:
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
        self.handles: dict[int, int] = {}  # entity -> body handle
        self._entity_of: dict[int, int] = {}  # body handle -> entity
        # per entity slot (its id's index bits): the entity whose body it is (-1: none), the body's row
        # in the library's shared buffers, the linear velocity last written to its Velocity
        self._owner = np.full(0, -1, np.int64)
        self._index = np.full(0, -1, np.int64)
        self._velocity = np.zeros((0, 3))
        # the bodies' handles sorted, and their entities (a ray hit's entity: raycast)
        self._by_handle: tuple[np.ndarray, np.ndarray] = (np.empty(0, np.uint64), np.empty(0, np.int64))
        self._seen = -1  # the world's structure version the bodies were last matched against
        self.steps = 0

    # ------------------------------------------------------------------ bodies
    def sync(self, world: Any) -> None:
        """Bodies made for new entities with Transform, RigidBody and Collider, and destroyed for
        those gone (or that lost one of them); nothing to do while the world's structure stands."""
        version = world.structure_version
        if version == self._seen:
            return
        self._seen = version
        batches = list(world.query(Transform, RigidBody, Collider, write=()))
        present = np.concatenate([b.entities for b in batches]) if batches else np.empty(0, np.int64)
        self._grow(int((present & INDEX_MASK).max()) + 1 if len(present) else 0)
        current = np.full(len(self._owner), -1, np.int64)  # slot -> the entity with a body there now
        current[present & INDEX_MASK] = present
        known = np.fromiter(self.handles, np.int64, len(self.handles))
        gone = known[current[known & INDEX_MASK] != known] if len(known) else known
        if len(gone):  # first: a new entity may have taken a gone one's slot
            handles = [self.handles.pop(int(e)) for e in gone]
            for h in handles:
                del self._entity_of[h]
            self.native.destroy_bodies_batch(handles)
            self._owner[gone & INDEX_MASK] = -1
        made = 0
        for batch in batches:
            new = self._owner[batch.entities & INDEX_MASK] != batch.entities
            if new.any():
                made += self._create(world, batch, np.flatnonzero(new))
        if made or len(gone):
            self.native.step(0.0)  # (the library makes and removes bodies at its next step)
            get = self.native.get_index
            for e, h in self.handles.items():  # a removal moves other bodies' rows
                self._index[e & INDEX_MASK] = get(h)
            by_handle = np.fromiter(self._entity_of, np.uint64, len(self._entity_of))
            order = np.argsort(by_handle)
            entities = np.fromiter(self._entity_of.values(), np.int64, len(by_handle))
            self._by_handle = (by_handle[order], entities[order])

    def _grow(self, slots: int) -> None:
        if slots > len(self._owner):
            more = max(slots, 2 * len(self._owner)) - len(self._owner)
            self._owner = np.concatenate([self._owner, np.full(more, -1, np.int64)])
            self._index = np.concatenate([self._index, np.full(more, -1, np.int64)])
            self._velocity = np.concatenate([self._velocity, np.zeros((more, 3))])

    def _create(self, world: Any, batch: Any, rows: np.ndarray) -> int:
        lib, create = self.lib, self.native.create_body
        body, col, t = batch[RigidBody], batch[Collider], batch[Transform]
        for r in rows:
            e = int(batch.entities[r])
            shape, size = int(col.shape[r]), col.size[r]
            if shape == BOX:
                extent: Any = tuple(float(s) for s in size)
            elif shape == SPHERE:
                extent = float(size[0])
            else:  # capsule, cylinder: the library takes (half height, radius)
                extent = (float(size[1]), float(size[0]))
            locked = int(body.locked[r])
            h = create(
                pos=tuple(float(x) for x in t.position[r]),
                rot=tuple(float(x) for x in t.rotation[r]),
                size=extent,
                shape=getattr(lib, _SHAPES[shape]),
                motion=getattr(lib, _MOTIONS[int(body.kind[r])]),
                user_data=e,
                is_sensor=bool(col.sensor[r]),
                mass=float(body.mass[r]),
                category=int(col.category[r]),
                mask=int(col.mask[r]),
                friction=float(col.friction[r]),
                restitution=float(col.restitution[r]),
                ccd=bool(body.ccd[r]),
                allowed_dofs=(63 & ~locked) if locked else 0,
            )
            self.handles[e] = h
            self._entity_of[h] = e
            self._owner[e & INDEX_MASK] = e
            velocity = world.get(e, Velocity).linear if world.has(e, Velocity) else np.zeros(3)
            if np.any(velocity):
                self.native.set_linear_velocity(h, *(float(v) for v in velocity))
            self._velocity[e & INDEX_MASK] = velocity
        return len(rows)

    # ------------------------------------------------------------------ the step
    def step(self, dt: float) -> None:
        self.native.step(float(dt))
        self.steps += 1

    def poses(self, entities: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The bodies' positions (float64) and rotations (x, y, z, w) of `entities`, gathered from
        the library's shared buffers."""
        rows = self._index[entities & INDEX_MASK]
        pos = np.frombuffer(self.native.positions, np.float64).reshape(-1, 4)[rows, :3]
        rot = np.frombuffer(self.native.rotations, np.float32).reshape(-1, 4)[rows].astype(np.float64)
        rot /= np.linalg.norm(rot, axis=1)[:, None]
        return pos, rot

    def velocities(self, entities: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The linear and angular velocities of `entities` (float64)."""
        rows = self._index[entities & INDEX_MASK]
        lin = np.frombuffer(self.native.velocities, np.float32).reshape(-1, 4)[rows, :3]
        ang = np.frombuffer(self.native.angular_velocities, np.float32).reshape(-1, 4)[rows, :3]
        return lin.astype(np.float64), ang.astype(np.float64)

    def last_velocity(self, entities: np.ndarray) -> np.ndarray:
        """The linear velocity last written into (or taken from) the Velocity of `entities`."""
        return self._velocity[entities & INDEX_MASK]

    def wrote_velocity(self, entities: np.ndarray, linear: np.ndarray) -> None:
        self._velocity[entities & INDEX_MASK] = linear

    def set_velocity(self, entity: int, linear: Any) -> None:
        """Give `entity`'s body this linear velocity (m/s) now."""
        v = [float(x) for x in linear]
        self.native.set_linear_velocity(self.handles[entity], *v)
        self._velocity[entity & INDEX_MASK] = v

    def entity_of(self, handle: int) -> int:
        """The entity of a body handle (-1: none)."""
        return self._entity_of.get(int(handle), -1)

    # ------------------------------------------------------------------ queries
    def raycast(self, origins: Any, directions: Any, max_distance: float = 1000.0) -> RayHits:
        """Cast every ray (rows of `origins` and `directions`, which need not be unit length) in
        one batch: the first body each one hits within `max_distance`."""
        o = np.ascontiguousarray(np.asarray(origins, np.float64).reshape(-1, 3))
        d = np.asarray(directions, np.float64).reshape(-1, 3)
        if len(o) != len(d):
            raise ValueError(f"raycast: {len(o)} origins but {len(d)} directions")
        if not (np.isfinite(o).all() and np.isfinite(d).all()):
            raise ValueError("raycast: origins and directions must be finite")
        length = np.linalg.norm(d, axis=1)
        if len(d) and length.min() == 0.0:
            raise ValueError(f"raycast: direction {int(np.argmin(length))} has zero length")
        unit = (d / length[:, None]).astype(np.float32) if len(d) else d.astype(np.float32)
        raw = self.native.raycast_batch(o.astype(np.float32).ravel(), unit.ravel(), float(max_distance))
        hits = np.frombuffer(raw, _HIT)
        hit = hits["handle"] != 0
        entity = np.full(len(o), -1, np.int64)
        handles, entities = self._by_handle
        if hit.any() and len(handles):
            at = np.minimum(np.searchsorted(handles, hits["handle"]), len(handles) - 1)
            known = hit & (handles[at] == hits["handle"])
            entity[known] = entities[at[known]]
            hit = known
        distance = np.where(hit, hits["fraction"].astype(np.float64) * max_distance, np.nan)
        point = np.where(hit[:, None], o + unit * distance[:, None], np.nan)
        normal = np.where(hit[:, None], hits["normal"].astype(np.float64), np.nan)
        return RayHits(entity, distance, point, normal)
