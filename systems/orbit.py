"""Move entities with Orbit along their circle (the seed scene's point-light animation)."""

from __future__ import annotations

import math

import numpy as np

from ecs_engine import native
from ecs_engine.components.orbit import Orbit
from ecs_engine.components.transform import Transform
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.ecs.world import World

TAU = 2.0 * math.pi


def orbit_step(
    center: np.ndarray,
    radius: np.ndarray,
    angular_speed: np.ndarray,
    phase: np.ndarray,
    height: np.ndarray,
    position: np.ndarray,
    dt: float,
) -> None:
    """Advance phase (kept in [0, 2*pi)) and write the positions, in place, for n rows. One
    native call (a handful of lights would pay ~10 us for the NumPy version's calls)."""
    if _orbit_native is not None:
        _orbit_native(center, radius, angular_speed, phase, height, position, float(dt))
    else:
        orbit_step_numpy(center, radius, angular_speed, phase, height, position, dt)


def orbit_step_numpy(
    center: np.ndarray,
    radius: np.ndarray,
    angular_speed: np.ndarray,
    phase: np.ndarray,
    height: np.ndarray,
    position: np.ndarray,
    dt: float,
) -> None:
    """Reference version of `orbit_step`."""
    phase += angular_speed * dt
    np.remainder(phase, TAU, out=phase)
    position[:, 0] = center[:, 0] + radius * np.cos(phase)
    position[:, 1] = center[:, 1] + height
    position[:, 2] = center[:, 2] + radius * np.sin(phase)


def _orbit_kernel(center, radius, angular_speed, phase, height, position, dt):  # pragma: no cover
    for i in range(phase.shape[0]):
        p = np.remainder(phase[i] + angular_speed[i] * dt, TAU)
        phase[i] = p
        position[i, 0] = center[i, 0] + radius[i] * np.cos(p)
        position[i, 1] = center[i, 1] + height[i]
        position[i, 2] = center[i, 2] + radius[i] * np.sin(p)


_orbit_native = native.njit(_orbit_kernel)


class OrbitSystem(System):
    """Column-wise over every table with Orbit and Transform; no per-entity Python."""

    def __init__(self) -> None:
        super().__init__(reads=[], writes=[Orbit, Transform], name="orbit", run_if=any_with(Orbit, Transform))

    def run(self, world: World, dt: float) -> None:
        for batch in world.query(Orbit, Transform):
            o = batch[Orbit]
            orbit_step(o.center, o.radius, o.angular_speed, o.phase, o.height, batch[Transform].position, float(dt))
