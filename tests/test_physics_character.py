"""The character controller (CharacterController): it walks, falls, lands, jumps as high as its
speed says, climbs steps below its step height and slopes below its steepest, is stopped by
what is higher or steeper, pushes dynamic bodies and is pushed by them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from physics_world import G, floor, physics_plugin

from ecs_engine import App, MinimalPlugins
from ecs_engine.components import Transform
from ecs_engine.components.physics import BOX, STATIC, CharacterController, Collider, RigidBody


def run(setup, frames, steer=None):
    """Each step's (position, grounded) of the world's character, over a run of `setup`;
    `steer(world, step, entity)` may change its CharacterController before each step."""
    seen, made = [], {}

    def control(world, dt):
        from ecs_engine import Time

        e = made.setdefault("who", next(iter(world.query(CharacterController).entities())))
        if steer is not None:
            steer(world, world.resources[Time].steps, e)

    def watch(world, dt):
        e = made["who"]
        seen.append((world.get(e, Transform).position, bool(world.get(e, CharacterController).grounded)))

    app = App(title="character").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("fixed", control)
    app.add_systems("update", watch)
    app.run(frames=frames)
    return app.world, seen


def walker(at=(0.0, 0.9, 0.0), walk=(0.0, 0.0, 0.0), **more):
    return Transform(position=at), CharacterController(walk=walk, **more)


def block(world, centre, half, rotation=(0.0, 0.0, 0.0, 1.0)):
    world.spawn(Transform(position=centre, rotation=rotation), RigidBody(kind=STATIC), Collider(shape=BOX, size=half))


def test_it_walks_on_the_ground_at_its_speed():
    def setup(world, dt):
        floor(world)
        world.spawn(*walker(walk=(3.0, 0.0, 0.0)))

    _, seen = run(setup, 61)
    where = np.array([p for p, _ in seen])
    assert where[-1, 0] - where[0, 0] == pytest.approx(3.0, rel=0.05)  # 1 s at 3 m/s
    assert np.abs(where[:, 1] - 0.9).max() < 0.03 and np.abs(where[:, 2]).max() < 1e-6
    assert all(g for _, g in seen[5:])


def test_it_falls_lands_and_jumps_as_high_as_its_speed_says():
    v = 5.0

    def setup(world, dt):
        floor(world)
        world.spawn(*walker(at=(0.0, 5.0, 0.0)))

    def steer(world, step, e):
        if step == 90:  # landed by then: jump
            c = world.get(e, CharacterController)
            world.set(e, CharacterController, jump=v, **{k: getattr(c, k) for k in ("walk",)})

    _, seen = run(setup, 180, steer)
    heights = np.array([p[1] for p, _ in seen])
    landed = next(i for i, (_, g) in enumerate(seen) if g)
    assert landed / 60 == pytest.approx(math.sqrt(2 * 4.1 / G), abs=0.1)  # fell 4.1 m
    assert heights[landed:90].min() == pytest.approx(0.9, abs=0.03)
    apex = heights[90:].max() - 0.9
    assert apex == pytest.approx(v * v / (2 * G), rel=0.1)
    assert seen[-1][1] and heights[-1] == pytest.approx(0.9, abs=0.03)  # down again


@pytest.mark.parametrize(("rise", "climbs"), [(0.3, True), (0.6, False)])
def test_it_walks_up_a_step_below_its_step_height_only(rise, climbs):
    def setup(world, dt):
        floor(world)
        block(world, (3.0, rise / 2, 0.0), (1.0, rise / 2, 3.0))  # a step from x = 2
        world.spawn(*walker(walk=(2.0, 0.0, 0.0)))  # step_height 0.4

    _, seen = run(setup, 90)
    x, y, _ = seen[-1][0]
    if climbs:
        assert x > 2.5 and y == pytest.approx(0.9 + rise, abs=0.05)
    else:
        assert x == pytest.approx(2.0 - 0.4, abs=0.05) and y == pytest.approx(0.9, abs=0.03)  # against it


@pytest.mark.parametrize(("degrees", "climbs"), [(30.0, True), (60.0, False)])
def test_it_walks_up_a_slope_below_its_steepest_only(degrees, climbs):
    a = math.radians(degrees)

    def setup(world, dt):
        floor(world)
        # a ramp rising toward +x from x = 1 (a long box turned about z, its top face through (1, 0))
        q = (0.0, 0.0, math.sin(a / 2), math.cos(a / 2))
        normal = np.array([-math.sin(a), math.cos(a), 0.0])
        along = np.array([math.cos(a), math.sin(a), 0.0])
        centre = np.array([1.0, 0.0, 0.0]) + along * 10.0 - normal * 0.5
        block(world, tuple(centre), (10.0, 0.5, 3.0), q)
        world.spawn(*walker(walk=(2.0, 0.0, 0.0)))  # max_slope 45 degrees

    _, seen = run(setup, 150)
    y = seen[-1][0][1]
    if climbs:
        assert y > 0.9 + 1.5  # 2.5 s up the ramp
    else:
        assert y < 0.9 + 0.6


def test_it_pushes_a_dynamic_box():
    made = {}

    def setup(world, dt):
        floor(world)
        made["box"] = world.spawn(Transform(position=(2.0, 0.5, 0.0)), RigidBody(mass=5.0), Collider(shape=BOX))
        world.spawn(*walker(walk=(2.0, 0.0, 0.0), strength=200.0))

    world, seen = run(setup, 120)
    assert world.get(made["box"], Transform).position[0] > 3.0  # shoved along +x
    assert seen[-1][0][0] > 1.5


def pushed_by_a_ball(mass):
    """Where a character standing at the origin is after a `mass` kg ball rolled at it at 6 m/s
    along +x (and another rolled past it, 3 m aside), and where that ball is."""
    from ecs_engine.components import Velocity
    from ecs_engine.components.physics import SPHERE

    made = {}

    def setup(world, dt):
        floor(world)
        for z, name in ((0.0, "ball"), (3.0, "miss")):
            made[name] = world.spawn(
                Transform(position=(-3.0, 0.3, z)),
                RigidBody(mass=mass),
                Collider(shape=SPHERE, size=(0.3, 0.3, 0.3)),
                Velocity(linear=(6.0, 0.0, 0.0)),
            )
        world.spawn(*walker())

    world, seen = run(setup, 90)
    return seen[-1][0], world.get(made["ball"], Transform).position


def test_a_body_thrown_at_it_pushes_it_the_more_the_heavier_it_is():
    """A ball rolled into a character standing still shoves it along the ball's way (not
    aside, and the ball does not go through it); a heavier ball at the same speed shoves it
    further."""
    at = {}
    for mass in (5.0, 40.0):
        character, ball = pushed_by_a_ball(mass)
        assert character[0] > 0.3, f"a {mass} kg ball at 6 m/s moved the character only to x={character[0]:.3f}"
        assert abs(character[2]) < 0.05
        assert ball[0] < character[0]
        at[mass] = character[0]
    assert at[40.0] > at[5.0] + 0.2, at
