"""A bot that plays asteroids (`--autoplay`): it fills the ShipControls resource each step, as
the keyboard would. It aims at the nearest asteroid with lead (the shot's travel time against
the asteroid's motion relative to the ship), fires when lined up, backs away from one about to
strike, and restarts after game over. A pure function of the world: runs are reproducible."""

from __future__ import annotations

import math

import numpy as np

from ecs_engine.components import Transform, Velocity
from ecs_engine.ecs import System, World

from .asteroids_game import Asteroid, Collider, Game, Ship, ShipControls, ShipSystem


def _near(world: World, at: np.ndarray, half: float, reach: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The asteroids within `reach` of `at` in x and z (the shortest way round the wrapping
    arena): their offsets (n, 3), velocities and radii. One pass of cheap NumPy over the
    columns, then work only on the few near ones."""
    offsets, speeds, radii = [], [], []
    for batch in world.query(Transform, Velocity, Collider, with_=(Asteroid,), write=()):
        p = batch[Transform].position
        dx = np.abs(p[:, 0] - at[0])
        dz = np.abs(p[:, 2] - at[2])
        span = 2.0 * half
        near = np.flatnonzero((np.minimum(dx, span - dx) < reach) & (np.minimum(dz, span - dz) < reach))
        if len(near):
            d = p[near] - at
            d[:, [0, 2]] = np.mod(d[:, [0, 2]] + half, span) - half
            offsets.append(d)
            speeds.append(batch[Velocity].linear[near])
            radii.append(batch[Collider].radius[near])
    if not offsets:
        return np.empty((0, 3)), np.empty((0, 3)), np.empty(0)
    return np.concatenate(offsets), np.concatenate(speeds), np.concatenate(radii)


class BotSystem(System):
    RANGE, DANGER, SEARCH = 35.0, 4.0, 60.0

    def __init__(self) -> None:
        super().__init__(reads=[Ship, Transform, Velocity, Asteroid, Collider, Game], writes=[ShipControls], name="bot")

    def run(self, world: World, dt: float) -> None:
        controls, game = world.resources[ShipControls], world.resources[Game]
        controls.turn, controls.thrust, controls.fire = 0.0, 0.0, False
        controls.restart = game.over
        ships = [b for b in world.query(Ship, Transform, Velocity) if len(b)]
        if game.over or not ships:
            return
        ship = ships[0]
        at, heading, velocity = ship[Transform].position[0], float(ship[Ship].heading[0]), ship[Velocity].linear[0]
        d, v, r = _near(world, at, game.half, self.SEARCH)
        if not len(d):
            controls.thrust = 0.6  # nothing near: cruise until something is
            return
        v = v - velocity
        distance = np.linalg.norm(d[:, [0, 2]], axis=1) - r
        nearest = int(np.argmin(distance))
        ahead = np.array([-math.sin(heading), 0.0, -math.cos(heading)])
        closing = np.einsum("ij,ij->i", d, v) < 0.0
        threat = (distance < self.DANGER) & closing
        if threat.any():
            towards = d[np.argmin(np.where(threat, distance, np.inf))]
            controls.thrust = -1.0 if towards @ ahead > 0.0 else 1.0
        if distance[nearest] > self.RANGE:
            controls.thrust = max(controls.thrust, 0.6)
            aim = d[nearest]
        else:
            lead = np.linalg.norm(d[nearest]) / ShipSystem.SHOT_SPEED
            aim = d[nearest] + v[nearest] * lead
        wanted = math.atan2(-aim[0], -aim[2])
        error = (wanted - heading + math.pi) % (2.0 * math.pi) - math.pi
        controls.turn = float(np.clip(error * 4.0, -1.0, 1.0))
        controls.fire = abs(error) < 0.06 and distance[nearest] < self.RANGE
