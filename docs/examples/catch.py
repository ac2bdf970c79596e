"""Catch: a paddle catches falling stars. The tutorial's game (docs/tutorial.md), complete,
through App:

    ecs-engine play docs/examples/catch.py                 # left / right, A / D or a stick move
    ecs-engine play docs/examples/catch.py --autoplay      # a bot plays
    ecs-engine play docs/examples/catch.py --autoplay --headless --frames 120 --screenshot out.png
    python docs/examples/catch.py
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field

import numpy as np

from ecs_engine import App, Component, DefaultPlugins, Field, system
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform, Velocity
from ecs_engine.maths.broad_phase import overlapping_pairs
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, Meshes, cube_mesh, materials, sphere_mesh
from ecs_engine.systems import ActionMap

ACTIONS = {"move": ["left/right", "a/d", "gamepad_left_x"]}  # -1 left, +1 right
WIDTH = 10.0  # stars fall over x in [-WIDTH, WIDTH]
STARS = 40  # in the sky at once


class Star(Component):
    points = Field(np.int32, default=10)


class Paddle(Component):
    width = Field(np.float64, default=2.0, finite=True, minimum=0.0)


class Caught(Component):
    """An event: the paddle caught `star`."""

    star = Field(np.int64, default=-1, entity=True)


@dataclass
class Score:
    points: int = 0
    missed: int = 0


@dataclass
class Sky:
    """Where stars come from: the game's random numbers (seeded: a run is reproducible), and
    the mesh and material a star is drawn with (made by `setup`)."""

    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(1))
    mesh: int = -1
    material: int = -1


def drop(world, n, low=18.0, high=34.0):
    """`n` new stars at random places above the screen, falling."""
    sky = world.resources[Sky]
    x, y = sky.rng.uniform(-WIDTH, WIDTH, n), sky.rng.uniform(low, high, n)
    world.spawn_batch(
        n,
        Transform(position=np.c_[x, y, np.zeros(n)]),
        Velocity(linear=(0.0, -4.0, 0.0)),
        Star(points=sky.rng.integers(1, 4, n) * 10),
        Mesh(handle=sky.mesh, material=sky.material),
    )


def setup(world, dt):
    """Once, before the first frame: meshes and materials, the paddle, a light, the camera."""
    meshes, looks, sky = world.resources[Meshes], materials(world), world.resources[Sky]
    sky.mesh = meshes.add(sphere_mesh(12, 8, radius=0.35))
    sky.material = looks.add(Material("star", base_color=(1.0, 0.8, 0.2, 1.0), emissive=(0.8, 0.55, 0.1)))
    blue = looks.add(Material("paddle", base_color=(0.2, 0.5, 1.0, 1.0), roughness=0.3))
    world.spawn(Transform(scale=(2.0, 0.4, 0.8)), Mesh(handle=meshes.add(cube_mesh()), material=blue), Paddle())
    world.spawn(Transform(rotation=look_rotation((-0.2, -1.0, -0.6))), DirectionalLight(illuminance=2.0))
    eye = np.array([0.0, 6.0, 22.0])
    world.spawn(Transform(position=eye, rotation=look_rotation(-eye * (1, 0, 1))), Camera(fov_y=math.radians(50)))
    drop(world, STARS, low=4.0)


@system(reads=[ActionMap], writes=[Transform])
def move_paddle(world, dt):
    """The player: the "move" action slides the paddle."""
    push = world.resources[ActionMap].axis("move")
    for batch in world.query(Transform, with_=[Paddle]):
        x = batch[Transform].position[:, 0]
        x[:] = np.clip(x + 12.0 * push * dt, -WIDTH, WIDTH)


@system(reads=[Paddle, Star], writes=[Transform])
def follow(world, dt):
    """The bot (--autoplay): the paddle moves towards the lowest falling star."""
    stars = world.query(Transform, with_=[Star]).column(Transform.position)
    for batch in world.query(Transform, with_=[Paddle]):
        x = batch[Transform].position[:, 0]
        if len(stars):
            low = stars[np.argmin(stars[:, 1])]
            x += np.clip(low[0] - x, -12.0 * dt, 12.0 * dt)


@system(reads=[Transform, Paddle, Star], writes=[Caught])
def catch(world, dt):
    stars = world.query(Transform, with_=[Star])
    at, ids = stars.column(Transform.position), stars.entities()
    paddles = world.query(Transform, with_=[Paddle]).column(Transform.position)
    _, hit = overlapping_pairs(paddles, 1.2, at, 0.35)
    if len(hit):
        world.events(Caught).send(Caught(star=ids[hit]))


@system(reads=[Caught, Star, Transform], writes=[Score, Sky])
def score(world, dt):
    """Caught stars score, fallen ones count as missed; both are replaced by new ones."""
    state = world.resources[Score]
    caught = np.unique(world.events(Caught).read().star)
    for star in caught:
        state.points += int(world.get(int(star), Star).points)
    gone = [b.entities[b[Transform].position[:, 1] < -1.0] for b in world.query(Transform, with_=[Star])]
    missed = np.setdiff1d(np.concatenate(gone) if gone else np.empty(0, np.int64), caught)
    state.missed += len(missed)
    ended = np.union1d(caught, missed).astype(np.int64)
    world.destroy(ended)  # at the stage's end
    drop(world, len(ended))


def hud(imgui, world):
    """The score, over the game."""
    state = world.resources[Score]
    imgui.set_next_window_pos((12.0, 12.0))
    imgui.begin("Catch", None, imgui.WindowFlags_.always_auto_resize.value)
    imgui.text(f"points {state.points}   missed {state.missed}")
    imgui.end()


def summary(world):
    """The line a run prints at its end."""
    state = world.resources[Score]
    return f"catch: {state.points} points, {state.missed} missed"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The game's own options on `ecs-engine play catch.py ...`."""
    parser.add_argument("--autoplay", action="store_true", help="a bot moves the paddle")
    parser.add_argument("--seed", type=int, default=1, help="where the stars fall (default 1)")


def build(app: App) -> None:
    autoplay, seed = getattr(app.options, "autoplay", False), getattr(app.options, "seed", 1)
    app.title = "Catch"
    app.add_plugins(DefaultPlugins)
    app.add_actions(ACTIONS)
    app.insert_resource(Score())
    app.insert_resource(Sky(np.random.default_rng(seed)))
    app.add_startup_systems(setup)
    app.add_systems("update", move_paddle)
    app.add_systems("update", follow, run_if=lambda world: autoplay)
    app.add_systems("update", catch, score)
    app.add_ui(hud)
    app.set_summary(summary)


if __name__ == "__main__":
    app = App(size=(1280, 720))
    build(app)
    app.run()
