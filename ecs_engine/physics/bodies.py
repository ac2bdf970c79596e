"""The bodies of a PhysicsWorld: which entity has which body, matched against the ECS when the
world's structure changes, with everything per body kept in arrays by entity slot (an entity
id's index bits) so that matching, moving rows and finding a hit's entity are NumPy, not a
Python loop over the bodies. Python runs per body only to make one (the library's call)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..components import AngularVelocity, Parent, Transform, Velocity
from ..components.physics import (
    BOX,
    CAPSULE,
    CONVEX_HULL,
    CYLINDER,
    DYNAMIC,
    HEIGHT_FIELD,
    KINEMATIC,
    MESH,
    SPHERE,
    STATIC,
    Collider,
    RigidBody,
)
from ..ecs.entities import INDEX_MASK
from ..errors import UsageError
from .joints import Joints
from .mesh_shapes import make_from_mesh

MOTIONS = {DYNAMIC: "MOTION_DYNAMIC", KINEMATIC: "MOTION_KINEMATIC", STATIC: "MOTION_STATIC"}
SHAPES = {BOX: "SHAPE_BOX", SPHERE: "SHAPE_SPHERE", CAPSULE: "SHAPE_CAPSULE", CYLINDER: "SHAPE_CYLINDER"}


# what a body was made from (per slot): a change in a system remakes the body (rebuild_changed)
SPEC = np.dtype(
    [
        ("shape", np.uint8),
        ("size", np.float64, 3),
        ("friction", np.float64),
        ("restitution", np.float64),
        ("category", np.uint16),
        ("mask", np.uint16),
        ("sensor", np.bool_),
        ("mass", np.float64),
        ("ccd", np.bool_),
        ("locked", np.uint8),
    ]
)


def spec(batch: Any) -> np.ndarray:
    """What each row's body is made from (SPEC), but its kind (which `follow_kinds` changes
    without a new body)."""
    col, body = batch[Collider], batch[RigidBody]
    out = np.empty(len(batch), SPEC)
    for name in ("shape", "size", "friction", "restitution", "category", "mask", "sensor"):
        out[name] = getattr(col, name)
    for name in ("mass", "ccd", "locked"):
        out[name] = getattr(body, name)
    return out


class Bodies:
    """Per entity slot: the entity whose body it is (`owner`, -1: none), the body's `handle`, its
    `kind`, whether it is a `sensor`, its `row` in the library's shared buffers and the linear
    `velocity` and `angular` velocity last written to its Velocity and AngularVelocity.
    `generation` counts the times rows moved (bodies made or destroyed)."""

    def __init__(self, lib: Any, native: Any) -> None:
        self.lib, self.native = lib, native
        self.owner = np.full(0, -1, np.int64)
        self.handle = np.zeros(0, np.uint64)
        self.kind = np.zeros(0, np.uint8)
        self.row = np.full(0, -1, np.int64)
        self.velocity = np.zeros((0, 3))
        self.angular = np.zeros((0, 3))
        self.sensor = np.zeros(0, bool)
        self.spec = np.zeros(0, SPEC)
        self.sensors = 0  # bodies that are sensors
        self.by_handle = (np.empty(0, np.uint64), np.empty(0, np.int64))  # handles sorted, their entities
        self.generation = 0
        self.motions = 0  # counts the bodies whose kind changed (static, kinematic, dynamic)
        self._seen = -1  # the world's structure version last matched
        self.joints = Joints(lib, native)

    def __len__(self) -> int:
        return int((self.owner >= 0).sum())

    def entities(self) -> np.ndarray:
        """The entities that have a body."""
        return self.owner[self.owner >= 0]

    def handle_of(self, entity: int) -> int | None:
        slot = entity & INDEX_MASK
        return int(self.handle[slot]) if slot < len(self.owner) and self.owner[slot] == entity else None

    def entities_of(self, handles: np.ndarray) -> np.ndarray:
        """The entity of each body handle (-1: not a body of ours)."""
        known, entities = self.by_handle
        out = np.full(len(handles), -1, np.int64)
        if len(known) and len(handles):
            at = np.minimum(np.searchsorted(known, handles), len(known) - 1)
            found = known[at] == handles
            out[found] = entities[at[found]]
        return out

    def position_of(self, entity: int) -> np.ndarray:
        """The body's position now (the library's buffer)."""
        positions = np.frombuffer(self.native.positions, np.float64).reshape(-1, 4)
        return positions[self.row[entity & INDEX_MASK], :3].copy()

    def sync(self, world: Any) -> bool:
        """Bodies made for new entities with Transform, RigidBody and Collider, and destroyed for
        those gone (or that lost one of them); nothing to do while the world's structure stands.
        Whether any body was made or destroyed."""
        version = world.structure_version
        if version == self._seen:
            return False
        self._seen = version
        for batch in world.query(Transform, RigidBody, Collider, with_=(Parent,), write=()):
            raise UsageError(
                f"entity {int(batch.entities[0])}: a body moves in world space and cannot have a Parent "
                "(make the body the parent: its children follow it)"
            )
        batches = list(world.query(Transform, RigidBody, Collider, write=()))
        present = np.concatenate([b.entities for b in batches]) if batches else np.empty(0, np.int64)
        self._grow(int((present & INDEX_MASK).max()) + 1 if len(present) else 0)
        current = np.full(len(self.owner), -1, np.int64)  # slot -> the entity with those components now
        current[present & INDEX_MASK] = present
        known = np.flatnonzero(self.owner >= 0)
        gone = known[current[known] != self.owner[known]]
        if len(gone):  # first: a new entity may have taken a gone one's slot
            self.native.destroy_bodies_batch(self.handle[gone].tolist())
            self.owner[gone] = -1
        made = 0
        for batch in batches:
            new = np.flatnonzero(self.owner[batch.entities & INDEX_MASK] != batch.entities)
            if len(new):
                made += self._create(world, batch, new)
        changed = bool(made or len(gone))
        if changed:
            self._rows()
        self.joints.sync(world, self)  # (a joint may come or go without a body)
        return changed

    def _rows(self) -> None:
        """The bodies' rows in the buffers after bodies were made or destroyed."""
        self.native.step(0.0)  # (the library makes and removes bodies at its next step)
        ids = np.frombuffer(self.native.user_data, np.uint64)[: self.native.count].astype(np.int64)
        ours = (ids & INDEX_MASK) < len(self.owner)  # (a body made on `native` directly is not ours)
        ours[ours] = self.owner[ids[ours] & INDEX_MASK] == ids[ours]
        self.row[ids[ours] & INDEX_MASK] = np.flatnonzero(ours)  # a removal moved other bodies' rows
        slots = np.flatnonzero(self.owner >= 0)
        order = np.argsort(self.handle[slots])
        self.by_handle = (self.handle[slots][order], self.owner[slots][order])
        self.sensors = int(self.sensor[self.owner >= 0].sum())
        self.generation += 1

    def _grow(self, slots: int) -> None:
        if slots > len(self.owner):
            more = max(slots, 2 * len(self.owner)) - len(self.owner)
            self.owner = np.concatenate([self.owner, np.full(more, -1, np.int64)])
            self.handle = np.concatenate([self.handle, np.zeros(more, np.uint64)])
            self.kind = np.concatenate([self.kind, np.zeros(more, np.uint8)])
            self.row = np.concatenate([self.row, np.full(more, -1, np.int64)])
            self.velocity = np.concatenate([self.velocity, np.zeros((more, 3))])
            self.angular = np.concatenate([self.angular, np.zeros((more, 3))])
            self.sensor = np.concatenate([self.sensor, np.zeros(more, bool)])
            self.spec = np.concatenate([self.spec, np.zeros(more, SPEC)])

    def _create(self, world: Any, batch: Any, rows: np.ndarray) -> int:
        """Bodies for `rows` of `batch`: each one a library call, with the rows' values taken
        out of the columns in bulk first (Python per body costs more than the call)."""
        lib, native = self.lib, self.native
        body, col, t = batch[RigidBody], batch[Collider], batch[Transform]
        entities = batch.entities[rows]
        shapes, kinds, locked = col.shape[rows].tolist(), body.kind[rows].tolist(), body.locked[rows].tolist()
        sizes, positions, rotations = col.size[rows].tolist(), t.position[rows].tolist(), t.rotation[rows].tolist()
        sensors, masses, ccd = col.sensor[rows].tolist(), body.mass[rows].tolist(), body.ccd[rows].tolist()
        categories, masks = col.category[rows].tolist(), col.mask[rows].tolist()
        frictions, restitutions = col.friction[rows].tolist(), col.restitution[rows].tolist()
        shape_ids = {shape: getattr(lib, name) for shape, name in SHAPES.items()}
        motion_ids = {kind: getattr(lib, name) for kind, name in MOTIONS.items()}
        handles = []
        for k, e in enumerate(entities.tolist()):
            shape, size = shapes[k], sizes[k]
            if shape in (CONVEX_HULL, MESH, HEIGHT_FIELD):
                handles.append(make_from_mesh(world, lib, native, MOTIONS, e, shape, body, col, t, int(rows[k])))
                continue
            if shape == BOX:
                extent: Any = tuple(size)
            elif shape == SPHERE:
                extent = size[0]
            else:  # capsule, cylinder: the library takes (half height, radius)
                extent = (size[1], size[0])
            handles.append(
                native.create_body(
                    pos=tuple(positions[k]),
                    rot=tuple(rotations[k]),
                    size=extent,
                    shape=shape_ids[shape],
                    motion=motion_ids[kinds[k]],
                    user_data=e,
                    is_sensor=sensors[k],
                    mass=masses[k],
                    category=categories[k],
                    mask=masks[k],
                    friction=frictions[k],
                    restitution=restitutions[k],
                    ccd=ccd[k],
                    allowed_dofs=(63 & ~locked[k]) if locked[k] else 0,
                )
            )
        slots = entities & INDEX_MASK
        self.owner[slots], self.handle[slots], self.kind[slots] = entities, handles, kinds
        self.sensor[slots] = col.sensor[rows]
        self.spec[slots] = spec(batch)[rows]
        self._rates(world, entities, np.asarray(handles, np.uint64))
        return len(rows)

    def rebuild_changed(self, world: Any, batch: Any) -> bool:
        """Bodies of `batch` whose Collider or RigidBody (but its kind, unless to or from static)
        a system changed made again from their components, joints on them too: whether any
        was."""
        slots = batch.entities & INDEX_MASK
        kinds, was = batch[RigidBody].kind, self.kind[slots]
        static = (was != kinds) & ((was == STATIC) | (kinds == STATIC))  # (follow_kinds does the others)
        changed = np.flatnonzero((self.owner[slots] == batch.entities) & ((spec(batch) != self.spec[slots]) | static))
        if not len(changed):
            return False
        self.native.destroy_bodies_batch(self.handle[slots[changed]].tolist())
        self.owner[slots[changed]] = -1
        self.joints.forget(batch.entities[changed])
        self._create(world, batch, changed)
        self._rows()
        self.joints.sync(world, self)
        return True

    def _rates(self, world: Any, entities: np.ndarray, handles: np.ndarray) -> None:
        """New bodies given their entities' Velocity and AngularVelocity (where they have them and
        they are not zero), and those kept as the last written."""
        slots = entities & INDEX_MASK
        self.velocity[slots], self.angular[slots] = 0.0, 0.0
        first = int(entities[0])  # (a table has Velocity or not, AngularVelocity or not)
        for kind, field, rates, put in (
            (Velocity, "linear", self.velocity, self.native.set_linear_velocity),
            (AngularVelocity, "angular", self.angular, self.native.set_angular_velocity),
        ):
            if not world.has(first, kind):
                continue
            values = np.array([getattr(world.get(int(e), kind), field) for e in entities.tolist()])
            rates[slots] = values
            for k in np.flatnonzero(values.any(axis=1)).tolist():
                put(int(handles[k]), *values[k].tolist())

    def follow_kinds(self, entities: np.ndarray, kinds: np.ndarray) -> None:
        """Bodies whose RigidBody.kind a system changed between dynamic and kinematic take their
        new motion (to or from static, rebuild_changed makes them again: the library cannot
        move a body made static, and crashed when asked)."""
        slots = entities & INDEX_MASK
        was = self.kind[slots]
        for k in np.flatnonzero((was != kinds) & (was != STATIC) & (kinds != STATIC)).tolist():
            kind = int(kinds[k])
            self.native.set_motion_type(int(self.handle[slots[k]]), getattr(self.lib, MOTIONS[kind]))
            self.kind[slots[k]] = kind
            self.motions += 1
