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


def _wrapped(delta: np.ndarray, half: float) -> np.ndarray:
    """The shortest offsets in a wrapping arena (x and z)."""
    out = delta.copy()
    out[:, [0, 2]] = np.mod(out[:, [0, 2]] + half, 2.0 * half) - half
    return out


class BotSystem(System):
    RANGE, DANGER = 35.0, 4.0

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
        offsets, speeds, radii = [], [], []
        for batch in world.query(Transform, Velocity, Collider, with_=(Asteroid,)):
            offsets.append(_wrapped(batch[Transform].position - at, game.half))
            speeds.append(batch[Velocity].linear - velocity)
            radii.append(batch[Collider].radius)
        if not offsets:
            return
        d, v, r = np.concatenate(offsets), np.concatenate(speeds), np.concatenate(radii)
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
