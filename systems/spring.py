"""Damped springs: Transform.position and Velocity.linear pulled toward Spring.anchor."""

from __future__ import annotations

from ecs_engine.components import Spring, Transform, Velocity
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.ecs.world import World
from ecs_engine.maths.spring import INTEGRATORS, step


class SpringSystem(System):
    """One step of every spring per run, with the chosen integrator (see ecs_engine.maths.spring).
    The default, `implicit`, stays stable however stiff the spring and however long the step;
    `exact` is exact for constant anchors; the others are there to compare."""

    def __init__(self, integrator: str = "implicit") -> None:
        if integrator not in INTEGRATORS:
            raise ValueError(f"unknown integrator {integrator!r}; integrators: {', '.join(INTEGRATORS)}")
        springs = any_with(Transform, Velocity, Spring)
        super().__init__(reads=[Spring], writes=[Transform, Velocity], name="spring", run_if=springs)
        self.integrator = integrator

    def run(self, world: World, dt: float) -> None:
        for batch in world.query(Transform, Velocity, Spring):
            s = batch[Spring]
            step(
                self.integrator,
                batch[Transform].position,
                batch[Velocity].linear,
                s.anchor,
                s.stiffness,
                s.damping,
                s.mass,
                float(dt),
            )
