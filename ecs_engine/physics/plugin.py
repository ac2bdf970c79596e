"""PhysicsPlugin: the PhysicsWorld resource and PhysicsSystem, which steps it once per fixed step.

Per step, in bulk (NumPy over whole columns; Python per body only where one changed by hand):
bodies are made and destroyed as entities gain or lose Transform, RigidBody and Collider (the
world's structure changed); a Velocity set by a system since the last step is handed to its
body; kinematic bodies are moved to their Transform; the world steps; the dynamic bodies'
positions and rotations go into their Transform (the fixed step's interpolation draws between
steps), their velocities into Velocity and AngularVelocity where they have them."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..app.plugins import Plugin
from ..components import AngularVelocity, Transform, Velocity
from ..components.physics import DYNAMIC, KINEMATIC, Collider, RigidBody
from ..ecs.schedule import System, any_with
from .world import PhysicsWorld


class PhysicsSystem(System):
    """Steps the world's PhysicsWorld resource (see the module)."""

    def __init__(self) -> None:
        super().__init__(
            reads=[Transform, RigidBody, Collider, Velocity, AngularVelocity],
            writes=[Transform, Velocity, AngularVelocity],
            name="physics",
            run_if=any_with(RigidBody),
        )

    def run(self, world: Any, dt: float) -> None:
        physics = world.resources[PhysicsWorld]
        physics.sync(world)
        native = physics.native
        for batch in world.query(Transform, RigidBody, Collider, write=()):
            kinematic = np.flatnonzero(batch[RigidBody].kind == KINEMATIC)
            t = batch[Transform]
            for r in kinematic:  # moved by the game: follow its Transform
                h = physics.handles[int(batch.entities[r])]
                native.set_transform(h, tuple(map(float, t.position[r])), tuple(map(float, t.rotation[r])))
        for batch in world.query(Velocity, RigidBody, Collider, with_=(Transform,), write=()):
            dynamic = batch[RigidBody].kind == DYNAMIC
            ids, wanted = batch.entities[dynamic], batch[Velocity].linear[dynamic]
            for k in np.flatnonzero(np.any(wanted != physics.last_velocity(ids), axis=1)):
                physics.set_velocity(int(ids[k]), wanted[k])  # set by a system since the last step
        physics.step(dt)
        for batch in world.query(Transform, RigidBody, Collider):
            dynamic = batch[RigidBody].kind == DYNAMIC
            every = bool(dynamic.all())
            ids = batch.entities if every else batch.entities[dynamic]
            if not len(ids):
                continue
            pos, rot = physics.poses(ids)
            t = batch[Transform]
            if every:
                t.position[:], t.rotation[:] = pos, rot
            else:
                t.position[dynamic], t.rotation[dynamic] = pos, rot
        for batch in world.query(Velocity, RigidBody, Collider, with_=(Transform,)):
            dynamic = batch[RigidBody].kind == DYNAMIC
            lin, _ = physics.velocities(batch.entities[dynamic])
            batch[Velocity].linear[dynamic] = lin
            physics.wrote_velocity(batch.entities[dynamic], lin)
        for batch in world.query(AngularVelocity, RigidBody, Collider, with_=(Transform,)):
            dynamic = batch[RigidBody].kind == DYNAMIC
            batch[AngularVelocity].angular[dynamic] = physics.velocities(batch.entities[dynamic])[1]


class PhysicsPlugin(Plugin):
    """Rigid-body physics (the `physics` extra): a PhysicsWorld resource with `gravity`, the
    library's `threads` and `max_bodies`, stepped by PhysicsSystem in the fixed stage. Without
    the library, adding the plugin is one UsageError naming the extra to install."""

    def __init__(
        self,
        gravity: tuple[float, float, float] = (0.0, -9.81, 0.0),
        threads: int | None = None,
        max_bodies: int = 65_536,
    ) -> None:
        self.gravity, self.threads, self.max_bodies = gravity, threads, max_bodies

    def build(self, app: Any) -> None:
        app.insert_resource(PhysicsWorld(self.gravity, self.threads, self.max_bodies))
        app.add_systems("fixed", PhysicsSystem())
