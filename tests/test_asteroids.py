"""The asteroids game (demos/asteroids*.py) as systems, without a GPU: a hit splits an asteroid
and scores, the ship loses health and the game ends and restarts, levels add asteroids, the
arena wraps, and a seeded autoplayed run is the same world every time."""

from __future__ import annotations

import numpy as np

from ecs_engine import World
from ecs_engine.components import Transform, Velocity
from ecs_engine.demos import asteroids
from ecs_engine.demos.asteroids_game import (
    LEVEL_ASTEROIDS,
    POINTS,
    Asteroid,
    Collider,
    Game,
    Projectile,
    Ship,
    ShipControls,
    spawn_asteroids,
)
from ecs_engine.demos.asteroids_hud import world_hash
from ecs_engine.ecs.timestep import FixedTimestep


class Meshes:
    def __init__(self) -> None:
        self.count = 0

    def add(self, mesh) -> int:
        self.count += 1
        return self.count - 1


def game_world(seed: int = 1, autoplay: bool = False):
    world = World()
    asteroids.build_world(world, Meshes().add, seed=seed, autoplay=autoplay)
    return world, asteroids.schedule(autoplay=autoplay), FixedTimestep(1 / 60)


def frames(world, schedule, clock, n: int) -> None:
    for _ in range(n):
        schedule.run_frame(world, 1 / 60, clock)


def only_rock(world: World, at, size: int) -> int:
    """Clear the field but for one asteroid of class `size` at `at`, standing still."""
    world.destroy(world.query(Asteroid).entities())
    game = world.resources[Game]
    spawn_asteroids(world, game, 1, size, at=np.array([at], np.float64))
    rock = int(world.query(Asteroid).entities()[0])
    world.set(rock, Velocity(linear=(0.0, 0.0, 0.0)))
    return rock


def test_a_shot_splits_an_asteroid_and_scores():
    world, schedule, clock = game_world()
    rock = only_rock(world, (0.0, 0.0, -6.0), 2)  # big, straight ahead of the ship
    world.resources[ShipControls].fire = True
    frames(world, schedule, clock, 1)
    world.resources[ShipControls].fire = False
    frames(world, schedule, clock, 30)
    game = world.resources[Game]
    assert not world.is_alive(rock)
    assert game.score == POINTS[2] and game.kills == 1
    sizes = sorted(world.query(Asteroid).column(Asteroid.size).tolist())
    assert sizes == [1, 1]  # two medium pieces
    assert world.query(Projectile).count() == 0  # the shot is gone


def test_contact_costs_health_then_grace_then_game_over_and_restart():
    world, schedule, clock = game_world()
    game = world.resources[Game]
    ship = int(world.query(Ship).entities()[0])
    world.set(ship, Ship(invulnerable=0.0))
    only_rock(world, (0.0, 0.0, 0.0), 2)  # on top of the ship
    frames(world, schedule, clock, 2)
    assert game.health == 70.0  # 10 x (class 2 + 1)
    frames(world, schedule, clock, 30)
    assert game.health == 70.0  # 1.5 s of grace
    game.health = 10.0
    frames(world, schedule, clock, 120)
    assert game.over and game.health == 0.0
    world.resources[ShipControls].restart = True
    frames(world, schedule, clock, 1)
    assert not game.over and game.health == 100.0 and game.score == 0
    assert world.query(Asteroid).count() == LEVEL_ASTEROIDS[0] and world.query(Ship).count() == 1


def test_levels_add_asteroids_and_the_arena_wraps():
    world, schedule, clock = game_world()
    game = world.resources[Game]
    half = game.half
    game.score = game.next_level_score()
    frames(world, schedule, clock, 1)
    assert game.level == 2 and world.query(Asteroid).count() >= LEVEL_ASTEROIDS[1] and game.half > half
    ship = int(world.query(Ship).entities()[0])
    world.set(
        ship,
        Transform(position=(game.half - 0.01, 0.0, 0.0)),
    )
    world.set(ship, Velocity(linear=(5.0, 0.0, 0.0)))
    frames(world, schedule, clock, 2)
    x = world.get(ship, Transform).position[0]
    assert -game.half <= x < -game.half + 1.0  # came back on the other side
    for batch in world.query(Transform, with_=(Collider,)):
        assert (np.abs(batch[Transform].position[:, [0, 2]]) <= game.half).all()


def test_a_seeded_autoplayed_run_is_the_same_world_every_time():
    results = []
    for seed in (1, 1, 2):
        world, schedule, clock = game_world(seed, autoplay=True)
        frames(world, schedule, clock, 240)
        game = world.resources[Game]
        results.append((game.score, game.shots, world_hash(world)))
    assert results[0] == results[1]
    assert results[0][2] != results[2][2]
    assert results[0][0] > 0 and results[0][1] > 0  # the bot shoots and scores
