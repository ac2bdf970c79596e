"""PhysicsPlugin: the PhysicsWorld resource and PhysicsSystem, which steps it once per fixed step.

Per step, in bulk (NumPy over whole columns; Python per body only where one changed by hand):
- bodies, joints and characters are made and destroyed as entities gain or lose their
  components (when the world's structure changed);
- a body whose Collider or RigidBody a system changed is made again; one whose Transform a
  system wrote is put there; a Velocity or AngularVelocity set by a system is handed to its
  body; kinematic bodies follow their Transform; gravity scales, damping and joint motors are
  applied; characters move;
- the world steps;
- the dynamic bodies' positions and rotations go into their Transform (the fixed step's
  interpolation draws between steps), their velocities into Velocity and AngularVelocity where
  they have them; contacts become events."""

from __future__ import annotations

import inspect
import time
from typing import Any

import numpy as np

from ..app.plugins import Plugin
from ..components import AngularVelocity, Mesh, Transform, Velocity
from ..components.physics import (
    DYNAMIC,
    KINEMATIC,
    STATIC,
    CharacterController,
    Collider,
    Contact,
    HeightField,
    Joint,
    RigidBody,
    Trigger,
)
from ..ecs.entities import INDEX_MASK
from ..ecs.schedule import System, any_with
from ..jobs import JobPool
from .contacts import send_contacts
from .physics_world import PhysicsWorld

_SETTINGS = ", ".join(inspect.signature(PhysicsWorld).parameters)
# the rates a body shares with its components: (component, field, angular)
_RATES = ((Velocity, "linear", False), (AngularVelocity, "angular", True))


# the columns a body is made from: another write tick on one, and the table's bodies are looked at
_BODY_COLUMNS = [(kind, name) for kind in (RigidBody, Collider) for name in kind.__fields__]


def _ticks(table: Any) -> tuple[int, int]:
    """The write ticks of a table's Transform position and rotation columns."""
    ticks = table.column_ticks
    return ticks[(Transform, "position")], ticks[(Transform, "rotation")]


class _TablePlan:
    """What a step does with one table of bodies, kept while the world's structure, the bodies'
    rows in the library and the table's RigidBody and Collider columns stand: its dynamic rows, their
    entities and rows in the library's buffers, its kinematic rows, its static rows (`still`), and
    the Transform columns' write ticks after the last step (`written`: another tick since, a
    system moved some body: a dynamic or static one is put there)."""

    __slots__ = (
        "dynamic",
        "entities",
        "key",
        "kinematic",
        "rows",
        "still",
        "tuned",
        "written",
    )

    def __init__(self, key: tuple, batch: Any, physics: PhysicsWorld) -> None:
        kinds = batch[RigidBody].kind
        dynamic = np.flatnonzero(kinds == DYNAMIC)
        self.key = key
        self.dynamic = dynamic
        self.entities = batch.entities[dynamic]
        self.rows = physics.rows(self.entities)
        self.kinematic = np.flatnonzero(kinds == KINEMATIC)
        self.still = np.flatnonzero(kinds == STATIC)
        self.written: tuple[int, int] | None = None
        # dynamic bodies with their own gravity scale or damping (the library has neither per
        # body): (their rows in the buffers, handles, masses, scales, linear and angular damping)
        body = batch[RigidBody]
        scale, linear, angular = (
            body.gravity_scale[dynamic],
            body.linear_damping[dynamic],
            body.angular_damping[dynamic],
        )
        tuned = np.flatnonzero((scale != 1.0) | (linear > 0.0) | (angular > 0.0))
        self.tuned = None
        if len(tuned):
            handles = physics.bodies.handle[self.entities[tuned] & INDEX_MASK]
            self.tuned = (
                self.rows[tuned],
                handles,
                body.mass[dynamic][tuned],
                scale[tuned],
                linear[tuned],
                angular[tuned],
            )


class PhysicsSystem(System):
    """Steps the world's PhysicsWorld resource (see the module)."""

    def __init__(self) -> None:
        super().__init__(
            reads=[
                Transform,
                RigidBody,
                Collider,
                Joint,
                Mesh,
                HeightField,
                Velocity,
                AngularVelocity,
                CharacterController,
            ],
            writes=[Transform, Velocity, AngularVelocity, CharacterController, Contact, Trigger],
            name="physics",
            run_if=any_with(RigidBody) | any_with(CharacterController),
        )
        self._plans: dict[int, _TablePlan] = {}  # by table id

    def _plan_all(self, world: Any, physics: PhysicsWorld) -> None:
        """Each table's plan, made again where its key changed, keeping the Transform's write
        ticks the last step saw (a body a system put somewhere in a frame that also made or
        destroyed one is still followed). A body made again (a Collider or RigidBody a system
        changed) moves other bodies' rows: every plan is made again then."""
        while True:
            rebuilt = False
            for batch in world.query(Transform, RigidBody, Collider, write=()):
                table = batch.table
                made_from = tuple(table.column_ticks[key] for key in _BODY_COLUMNS)
                key = (world.structure_version, physics.bodies.generation, made_from)
                plan = self._plans.get(table.id)
                if plan is not None and plan.key == key:
                    continue
                physics.bodies.follow_kinds(batch.entities, batch[RigidBody].kind)  # changed by a system
                if plan is not None and plan.key[:2] == key[:2] and physics.bodies.rebuild_changed(world, batch):
                    rebuilt = True
                    break
                fresh = self._plans[table.id] = _TablePlan(key, batch, physics)
                if plan is not None:  # (a Transform a system wrote this frame is still to be followed)
                    fresh.written = plan.written
            if not rebuilt:
                return

    def run(self, world: Any, dt: float) -> None:
        physics = world.resources[PhysicsWorld]
        if physics.paused:
            if not physics.step_once:
                return
            physics.step_once = False
        physics.pool = world.resources.get(JobPool)
        physics.sync(world)  # (the plans follow: their keys hold the structure and the bodies' rows)
        self._plan_all(world, physics)
        plans = []
        for batch in world.query(Transform, RigidBody, Collider, write=()):
            plan = self._plans[batch.table.id]
            plans.append(plan)
            if len(plan.kinematic):  # moved by the game: the bodies follow their Transform
                physics.place(batch.entities[plan.kinematic], batch[Transform], plan.kinematic)
            if plan.written is not None and plan.written != _ticks(batch.table):  # teleported
                if len(plan.rows):
                    physics.follow_moved(plan.rows, plan.entities, batch[Transform], plan.dynamic)
                if len(plan.still):  # (their rows only now: a system seldom moves a static body)
                    still = batch.entities[plan.still]
                    physics.follow_moved(physics.rows(still), still, batch[Transform], plan.still)
        for kind, field, angular in _RATES:  # rates set by a system since the last step
            for batch in world.query(kind, RigidBody, Collider, with_=(Transform,), write=()):
                plan = self._plans[batch.table.id]
                wanted = getattr(batch[kind], field)[plan.dynamic]
                changed = np.any(wanted != physics.last_velocity(plan.entities, angular), axis=1)
                for k in np.flatnonzero(changed).tolist():
                    physics.set_velocity(int(plan.entities[k]), wanted[k], angular)
        for plan in plans:
            if plan.tuned is not None:
                physics.tune(*plan.tuned, dt)
        if physics.bodies.joints.motors:
            physics.bodies.joints.drive(world)
        if physics.characters.made:
            physics.characters.move(world, physics.gravity[1], dt)
        physics.step(dt)
        if physics.characters.made:
            physics.characters.write_back(world)
        contacts = physics.contacts  # (unread, the library's buffer stays at its cap)
        if contacts in ("begin_end", "all") or (contacts == "triggers" and physics.bodies.sensors):
            start = time.perf_counter()
            records = physics.native.get_contact_events_raw()  # a copy of the buffer, which it empties
            copied = time.perf_counter()
            send_contacts(world, physics, records, touches=contacts != "triggers", stays=contacts == "all")
            physics.events_ms = (time.perf_counter() - start) * 1e3
            physics.events_copy_ms = (copied - start) * 1e3
        for batch in world.query(Transform, RigidBody, Collider):
            plan = self._plans[batch.table.id]
            if len(plan.rows):
                t = batch[Transform]
                physics.write_poses(plan.rows, plan.dynamic, t.position, t.rotation)
            plan.written = _ticks(batch.table)
        for kind, field, angular in _RATES:
            for batch in world.query(kind, RigidBody, Collider, with_=(Transform,)):
                plan = self._plans[batch.table.id]
                rate = getattr(batch[kind], field)
                physics.write_velocities(plan.rows, plan.dynamic, None if angular else rate, rate if angular else None)
                physics.wrote_velocity(plan.entities, rate[plan.dynamic], angular)


class PhysicsPlugin(Plugin):
    """Rigid-body physics (the `physics` extra): a PhysicsWorld resource made with `settings`
    (PhysicsWorld's: `gravity`, the library's `threads`, `max_bodies`, which `contacts` become
    events), stepped by PhysicsSystem in the fixed stage. Without the library, adding the plugin
    is one UsageError naming the extra to install."""

    def __init__(self, **settings: Any) -> None:
        unknown = sorted(set(settings) - set(inspect.signature(PhysicsWorld).parameters))
        if unknown:
            raise TypeError(f"PhysicsPlugin: no setting {', '.join(unknown)} (PhysicsWorld takes {_SETTINGS})")
        self.settings = settings

    def build(self, app: Any) -> None:
        app.insert_resource(PhysicsWorld(**self.settings))
        app.add_systems("fixed", PhysicsSystem())
