"""The snapshot that interpolated drawing needs: at the head of the fixed-step stage, each fixed
step first copies Transform into PreviousTransform (where an entity has both), so the transform
system can draw it between its last two steps (see ecs.timestep and ecs.Schedule.run_frame)."""

from __future__ import annotations

from ecs_engine.components import PreviousTransform, Transform
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.ecs.world import World


class SnapshotSystem(System):
    def __init__(self) -> None:
        both = any_with(Transform, PreviousTransform)
        super().__init__(reads=[Transform], writes=[PreviousTransform], name="snapshot", run_if=both)

    def run(self, world: World, dt: float) -> None:
        for batch in world.query(Transform, PreviousTransform):
            t, prev = batch[Transform], batch[PreviousTransform]
            prev.position[...] = t.position
            prev.rotation[...] = t.rotation
