"""Move entities with Orbit along their circle (the seed scene's point-light animation)."""

from __future__ import annotations

import math

import numpy as np
from ecs_engine.components.orbit import Orbit
from ecs_engine.components.transform import Transform

from ecs_engine.schedule import System
from ecs_engine.world import World

TAU = 2.0 * math.pi


def orbit_step(center: np.ndarray, radius: np.ndarray, angular_speed: np.ndarray, phase: np.ndarray,
               height: np.ndarray, position: np.ndarray, dt: float) -> None:
    """Advance phase (kept in [0, 2*pi)) and write the positions, in place, for n rows."""
    phase += angular_speed * dt
    np.remainder(phase, TAU, out=phase)
    position[:, 0] = center[:, 0] + radius * np.cos(phase)
    position[:, 1] = center[:, 1] + height
    position[:, 2] = center[:, 2] + radius * np.sin(phase)


class OrbitSystem(System):
    """Column-wise over every table with Orbit and Transform; no per-entity Python."""

    def __init__(self) -> None:
        super().__init__(reads=[], writes=[Orbit, Transform], name="orbit")

    def run(self, world: World, dt: float) -> None:
        for batch in world.query(Orbit, Transform):
            o = batch[Orbit]
            orbit_step(o.center, o.radius, o.angular_speed, o.phase, o.height,
                       batch[Transform].position, float(dt))
