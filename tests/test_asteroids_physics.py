"""Asteroids with the physics (`play asteroids --physics`): asteroids bounce off one another
keeping their momentum, a bounce loses what the restitution says, and an asteroid that strikes
the ship shoves it and hurts it once."""

from __future__ import annotations

import numpy as np
import pytest
from physics_world import physics_plugin  # (skips the tests without the physics extra)

from ecs_engine import App, MinimalPlugins
from ecs_engine.components import AngularVelocity, Transform, Velocity
from ecs_engine.demos import asteroids
from ecs_engine.demos.asteroids_game import Asteroid, Game, Ship, spawn_asteroids
from ecs_engine.demos.asteroids_physics import RESTITUTION, momentum


class Meshes:
    def add(self, mesh) -> int:
        return 0


def play(arrange, frames: int, watch=None):
    """A physics game world whose field `arrange(world, game)` sets up, run `frames` fixed steps
    headless with no one at the controls; `watch(world)` after each frame."""
    physics_plugin()  # (skips the test without the library)
    from ecs_engine.app.plugins import HierarchyPlugin, MotionPlugin, TimePlugin

    app = App(title="asteroids physics").add_plugins(MinimalPlugins.without(TimePlugin, MotionPlugin, HierarchyPlugin))
    world = app.world
    asteroids.build_world(world, Meshes().add, seed=3, physics=True)
    world.destroy(world.query(Asteroid).entities())
    arrange(world, world.resources[Game])
    asteroids.add_game_systems(app, autoplay=False, controls=None, physics=True)
    if watch is not None:
        app.add_systems("update", watch)
    app.run(frames=frames)
    return app.world


def rocks(world, game, where, velocities, size=2):
    """Asteroids of class `size` at `where` moving at `velocities`, not spinning (a spinning one's
    friction turns some of a bounce into spin)."""
    spawn_asteroids(world, game, len(where), size, at=np.array(where, np.float64), velocity=np.array(velocities))
    world.set(world.query(Asteroid).entities(), AngularVelocity(angular=(0.0, 0.0, 0.0)))


def test_two_asteroids_bounce_apart_keeping_momentum_and_losing_what_restitution_says():
    seen = []

    def arrange(world, game):
        rocks(world, game, [(20.0, 0.0, 20.0), (30.0, 0.0, 20.0)], [(3.0, 0.0, 0.0), (-3.0, 0.0, 0.0)])

    def watch(world):
        v = [world.get(int(e), Velocity).linear.copy() for e in world.query(Asteroid).entities()]
        seen.append((v, momentum(world)))

    world = play(arrange, 150, lambda world, dt: watch(world))
    first, last = seen[0][0], seen[-1][0]
    assert first[0][0] > 2.9 and first[1][0] < -2.9  # heading for each other
    assert last[0][0] < 0.0 and last[1][0] > 0.0  # bounced back
    # the bounce, from a step before the touch to a step after (the library's own damping,
    # 0.05 per second, takes its share over longer spans: docs/physics.md)
    turn = next(i for i, (v, _) in enumerate(seen) if v[0][0] < 0.0)
    before, after = seen[turn - 2][0], seen[turn + 1][0]
    closing, parting = before[0][0] - before[1][0], after[1][0] - after[0][0]
    assert parting / closing == pytest.approx(RESTITUTION, abs=0.02)
    p = np.array([m for _, m in seen])
    assert np.abs(p - p[0]).max() < 1e-6 * np.abs(p[0]).max() + 1e-3  # the ship, still, adds nothing
    assert all(abs(world.get(int(e), Transform).position[1]) < 1e-6 for e in world.query(Asteroid).entities())


def test_an_asteroid_that_strikes_the_ship_shoves_it_and_hurts_it_once():
    seen = []

    def arrange(world, game):  # it arrives after the ship's first 2 s of grace
        rocks(world, game, [(-20.0, 0.0, 0.0)], [(8.0, 0.0, 0.0)])

    def watch(world, dt):
        ship = int(world.query(Ship).entities()[0])
        seen.append((world.get(ship, Velocity).linear.copy(), world.resources[Game].health))

    play(arrange, 200, watch)
    velocity, health = seen[-1]
    assert velocity[0] > 1.0  # shoved along the asteroid's way
    assert abs(velocity[2]) < 0.5
    assert health == 100.0 - 10.0 * 3  # a big one, once (then the grace time)
