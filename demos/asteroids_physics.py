"""Asteroids with its collisions resolved by the physics (`ecs-engine play asteroids --physics`,
the `physics` extra): asteroids and the ship are rigid spheres on the play plane (no gravity,
locked to y = 0), so asteroids bounce off one another and off the ship, and the ship is shoved
by what hits it. The ship is hurt when a contact begins (a Contact event, not the game's
overlap test); shots still hit asteroids through the game's broad phase (they are not bodies:
a shot's hit splits the asteroid, it does not bounce).

The bodies ride on the game's own entities: `bodies` is the Game resource's `bodies`, which
spawn_asteroids and start call for the components they add (asteroids.py sets it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ecs_engine.components import Velocity
from ecs_engine.components.physics import BEGIN, LOCK_ROTATION, LOCK_Y, SPHERE, Contact, RigidBody
from ecs_engine.components.physics import Collider as Body
from ecs_engine.ecs import System, World

from .asteroids_game import Asteroid, Game, Ship, ShipHit

DENSITY = 300.0  # kg per cubic metre of rock: a big asteroid (r = 2) weighs about 10 t
SHIP_MASS = 2_000.0  # kg: a medium asteroid (1.3 t) deflects it, a big one throws it
RESTITUTION = 0.8  # asteroids bounce, losing a little


def bodies(radii: np.ndarray, ship: bool = False) -> tuple[Any, Any]:
    """The RigidBody and Collider of asteroids of `radii` (their mass from DENSITY), or of the
    ship (SHIP_MASS, and it does not turn but as steered): Game.bodies."""
    radii = np.asarray(radii, np.float64)
    mass = np.full(len(radii), SHIP_MASS) if ship else DENSITY * 4.0 / 3.0 * np.pi * radii**3
    locked = LOCK_Y | LOCK_ROTATION if ship else LOCK_Y
    return (
        RigidBody(mass=mass, locked=locked),
        Body(shape=SPHERE, size=np.repeat(radii[:, None], 3, 1), restitution=RESTITUTION, friction=0.1),
    )


class ShipContactSystem(System):
    """A contact between the ship and an asteroid that begins this step is a ShipHit (the
    asteroid's size class), at most one a step, as the overlap test sent them."""

    def __init__(self) -> None:
        super().__init__(reads=[Contact, Asteroid, Ship, Game], writes=[ShipHit], name="ship_contacts")

    def run(self, world: World, dt: float) -> None:
        contacts = world.events(Contact).read()
        if not len(contacts) or world.resources[Game].over:
            return
        ships = world.query(Ship).entities()
        begun = contacts.phase == BEGIN
        for mine, theirs in ((contacts.a, contacts.b), (contacts.b, contacts.a)):
            hit = np.flatnonzero(begun & np.isin(mine, ships))
            for e in theirs[hit].tolist():
                if world.is_alive(e) and world.has(e, Asteroid):
                    world.events(ShipHit).send(ShipHit(int(world.get(e, Asteroid).size)))
                    return


def physics_plugin(threads: int | None = None) -> Any:
    """The PhysicsPlugin asteroids runs with: no gravity, contacts' beginnings and ends as events.
    Without the physics extra: one UsageError naming it."""
    from ecs_engine.physics import PhysicsPlugin

    settings: dict[str, Any] = {"gravity": (0.0, 0.0, 0.0), "contacts": "begin_end"}
    if threads is not None:
        settings["threads"] = threads
    return PhysicsPlugin(**settings)


def momentum(world: World) -> np.ndarray:
    """The total linear momentum of the asteroids and the ship (kg m/s): what bounces keep."""
    total = np.zeros(3)
    for batch in world.query(RigidBody, Velocity, write=()):
        total += (batch[RigidBody].mass[:, None] * batch[Velocity].linear).sum(axis=0)
    return total
