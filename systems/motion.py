"""Integrate Velocity and AngularVelocity into Transform."""

from __future__ import annotations

from ecs_engine.components import AngularVelocity, Transform, Velocity
from ecs_engine.schedule import System
from ecs_engine.transform_math import integrate_angular, integrate_linear
from ecs_engine.world import World


class MotionSystem(System):
    """Explicit step over dt: position += v*dt, rotation by the exact constant-rate quaternion."""

    def __init__(self) -> None:
        super().__init__(reads=[Velocity, AngularVelocity], writes=[Transform], name="motion")

    def run(self, world: World, dt: float) -> None:
        for batch in world.query(Transform, Velocity):
            integrate_linear(batch[Transform].position, batch[Velocity].linear, dt)
        for batch in world.query(Transform, AngularVelocity):
            integrate_angular(batch[Transform].rotation, batch[AngularVelocity].angular, dt)
