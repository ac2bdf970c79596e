"""Joint components made into the library's constraints, and destroyed with their entity, their
Joint or either body (matched when the world's structure changes, as bodies are); a joint whose
other body goes breaks, and its Joint is removed (`Joints._break`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..components import Transform
from ..components.physics import BALL, DISTANCE, FIXED, HINGE, JOINT_NAMES, SLIDER, Collider, Joint, RigidBody
from ..ecs.entities import INDEX_MASK
from ..errors import UsageError

_TYPES = {
    FIXED: "CONSTRAINT_FIXED",
    BALL: "CONSTRAINT_POINT",
    HINGE: "CONSTRAINT_HINGE",
    SLIDER: "CONSTRAINT_SLIDER",
    DISTANCE: "CONSTRAINT_DISTANCE",
}
FAR = 1e6  # an infinite slider or distance limit, as the library takes it (metres)


class Joints:
    """Per entity slot: its constraint's handle (0: none) and the entity it joins."""

    def __init__(self, lib: Any, native: Any) -> None:
        self.lib, self.native = lib, native
        self.handle = np.zeros(0, np.uint64)
        self.owner = np.full(0, -1, np.int64)
        self.target = np.full(0, np.nan)  # the motor target last handed to the library
        self.other = np.full(0, -1, np.int64)  # the entity joined to
        self.motors = 0  # joints with a motor

    def _grow(self, slots: int) -> None:
        if slots > len(self.handle):
            more = slots - len(self.handle)
            self.handle = np.concatenate([self.handle, np.zeros(more, np.uint64)])
            self.owner = np.concatenate([self.owner, np.full(more, -1, np.int64)])
            self.target = np.concatenate([self.target, np.full(more, np.nan)])
            self.other = np.concatenate([self.other, np.full(more, -1, np.int64)])

    def sync(self, world: Any, bodies: Any) -> None:
        """Constraints made for new joints between bodies, destroyed for joints gone."""
        batches = list(world.query(Joint, with_=(Transform, RigidBody, Collider), write=()))
        present = np.concatenate([b.entities for b in batches]) if batches else np.empty(0, np.int64)
        self._grow(max(len(bodies.owner), int((present & INDEX_MASK).max()) + 1 if len(present) else 0))
        current = np.full(len(self.owner), -1, np.int64)
        current[present & INDEX_MASK] = present
        known = np.flatnonzero(self.owner >= 0)
        gone = known[current[known] != self.owner[known]]
        self._drop(gone)
        broken = self._break(world, bodies)
        made = 0
        for batch in batches:
            new = np.flatnonzero(self.owner[batch.entities & INDEX_MASK] != batch.entities)
            if len(broken):  # (their Joint goes at the sync point: not made again meanwhile)
                new = new[~np.isin(batch.entities[new], broken)]
            for r in new.tolist():
                self._make(world, bodies, batch, r)
                made += 1
        if made:
            self.native.step(0.0)  # (a constraint takes a motor target once the library has made it)
        self.motors = sum(int(np.isfinite(b[Joint].target).sum()) for b in batches)

    def _break(self, world: Any, bodies: Any) -> np.ndarray:
        """The joints whose other body is gone (its entity destroyed, or without RigidBody or
        Collider now) break, as a rope whose anchor is taken away: the library destroyed their
        constraints with that body, and their Joint is removed from the entity at the sync
        point (a game sees it go: `world.has`, or an observer of Joint's removal). The entities."""
        live = np.flatnonzero(self.owner >= 0)
        others = self.other[live]
        slots = others & INDEX_MASK
        there = slots < len(bodies.owner)
        held = np.zeros(len(live), bool)
        held[there] = bodies.owner[slots[there]] == others[there]
        broken = live[~held]
        owners = self.owner[broken].copy()
        if len(owners):
            world.remove(owners, Joint)
        self._drop(broken)
        return owners

    def forget(self, entities: np.ndarray) -> None:
        """The joints on `entities`' bodies (which are made again) destroyed, to be made again by
        the next `sync`."""
        self._drop(np.flatnonzero((self.owner >= 0) & (np.isin(self.owner, entities) | np.isin(self.other, entities))))

    def _drop(self, slots: np.ndarray) -> None:
        """The constraints at `slots` destroyed and the slots emptied (a constraint that went with
        a destroyed body: the library ignores the call)."""
        for slot in slots.tolist():
            self.native.destroy_constraint(int(self.handle[slot]))
        self.owner[slots], self.handle[slots], self.target[slots] = -1, 0, np.nan

    def drive(self, world: Any) -> None:
        """Motor targets a system changed (or new motors') handed to the library."""
        for batch in world.query(Joint, with_=(Transform, RigidBody, Collider), write=()):
            slots, target = batch.entities & INDEX_MASK, batch[Joint].target
            wanted = np.isfinite(target) & (target != self.target[slots]) & (self.handle[slots] != 0)
            for r in np.flatnonzero(wanted).tolist():
                self.native.set_constraint_target(int(self.handle[slots[r]]), float(target[r]))
                self.target[slots[r]] = target[r]

    def _make(self, world: Any, bodies: Any, batch: Any, r: int) -> None:
        joint, e = batch[Joint], int(batch.entities[r])
        kind, other = int(joint.kind[r]), int(joint.other[r])
        mine, theirs = bodies.handle_of(e), bodies.handle_of(other) if other >= 0 else None
        if theirs is None:
            why = "which has no body (Transform, RigidBody, Collider)" if world.is_alive(other) else "not alive"
            raise UsageError(f"entity {e}: Joint.other is {other}, {why}")
        if other == e:
            raise UsageError(f"entity {e}: Joint.other is the entity itself")
        low, high = (float(x) for x in joint.limits[r])
        if math.isnan(low) or math.isnan(high) or low > high:
            raise UsageError(f"entity {e}: Joint.limits must be two numbers, the first not above the second")
        pivot, axis = tuple(joint.pivot[r].tolist()), tuple(joint.axis[r].tolist())
        if kind == HINGE:
            params: Any = (pivot, axis, max(low, -math.pi), min(high, math.pi))
        elif kind == SLIDER:
            params = (pivot, axis, max(low, -FAR), min(high, FAR))
        elif kind == BALL:
            params = (pivot,)
        elif kind == DISTANCE:
            if math.isinf(low) and math.isinf(high):  # as far apart as they start
                apart = float(np.linalg.norm(bodies.position_of(e) - bodies.position_of(other)))
                low = high = apart
            params = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), max(low, 0.0), min(high, FAR))  # (the centres, body space)
        else:
            params = None
        strength, motor = float(joint.strength[r]), None
        if math.isfinite(float(joint.target[r])):
            if kind not in (HINGE, SLIDER):
                raise UsageError(
                    f"entity {e}: a {JOINT_NAMES[kind]} Joint has no motor (Joint.target is for hinges and sliders)"
                )
            motor = {"max_torque": strength} if kind == HINGE else {"max_force": strength}
        try:
            made = self.native.create_constraint(getattr(self.lib, _TYPES[kind]), theirs, mine, params, motor)
        except (TypeError, ValueError) as exc:
            raise UsageError(f"entity {e}: a {JOINT_NAMES[kind]} Joint the library refused: {exc}") from None
        slot = e & INDEX_MASK
        self.handle[slot], self.owner[slot], self.other[slot] = made, e, other
