"""Integrate Velocity and AngularVelocity into Transform."""

from __future__ import annotations

import numpy as np

from ecs_engine.components import AngularVelocity, Transform, Velocity
from ecs_engine.components.physics import RigidBody
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.ecs.world import World
from ecs_engine.jobs import JobPool, over_rows
from ecs_engine.maths.transform import integrate_angular, integrate_linear


class MotionSystem(System):
    """Explicit step over dt: position += v*dt, rotation by the exact constant-rate quaternion.
    Large tables are split across the world's JobPool resource, if it has one."""

    def __init__(self) -> None:
        moving = any_with(Transform, Velocity) | any_with(Transform, AngularVelocity)
        super().__init__(reads=[Velocity, AngularVelocity], writes=[Transform], name="motion", run_if=moving)

    def run(self, world: World, dt: float) -> None:
        pool = world.resources.get(JobPool)
        # Tables with both rates: one batch of jobs, each chunk both kernels (a batch costs
        # ~0.1-0.4 ms to hand out at 16 threads).
        for batch in world.query(Transform, Velocity, AngularVelocity, without=(RigidBody,)):
            t, lin, ang = batch[Transform], batch[Velocity].linear, batch[AngularVelocity].angular

            def both(
                s: slice,
                pos: np.ndarray = t.position,
                rot: np.ndarray = t.rotation,
                lin: np.ndarray = lin,
                ang: np.ndarray = ang,
            ) -> None:
                integrate_linear(pos[s], lin[s], dt)
                integrate_angular(rot[s], ang[s], dt)

            over_rows(pool, len(batch), both)
        for batch in world.query(Transform, Velocity, without=(AngularVelocity, RigidBody)):
            pos, lin = batch[Transform].position, batch[Velocity].linear

            def linear(s: slice, pos: np.ndarray = pos, lin: np.ndarray = lin) -> None:
                integrate_linear(pos[s], lin[s], dt)

            over_rows(pool, len(batch), linear)
        for batch in world.query(Transform, AngularVelocity, without=(Velocity, RigidBody)):
            rot, ang = batch[Transform].rotation, batch[AngularVelocity].angular

            def angular(s: slice, rot: np.ndarray = rot, ang: np.ndarray = ang) -> None:
                integrate_angular(rot[s], ang[s], dt)

            over_rows(pool, len(batch), angular)
