"""Physics joints (Joint components): each keeps what it should as the bodies move."""

from __future__ import annotations

import numpy as np
import pytest
from physics_world import anchor, floor, physics_plugin

from ecs_engine import App, MinimalPlugins
from ecs_engine.components import AngularVelocity, Transform
from ecs_engine.components.physics import BALL, BOX, DISTANCE, FIXED, HINGE, SLIDER, SPHERE, Collider, Joint, RigidBody

# joints: bodies joined by one another's Joint, watched every step
NO_TOUCH = {"category": 2, "mask": 1}  # a joined body that collides with the ground only


def _watch(setup, frames, entities):
    """Each step's positions and rotations of `entities` over a run of `setup`."""
    seen = []

    def watch(world, dt):
        seen.append([(world.get(e, Transform).position, world.get(e, Transform).rotation) for e in entities()])

    app = App(title="joints").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", watch)
    app.run(frames=frames)
    return app.world, seen


def test_a_ball_joint_keeps_a_pendulum_at_its_length_as_it_swings():
    made = {}

    def setup(world, dt):
        made["top"] = anchor(world, (0.0, 5.0, 0.0))
        made["bob"] = world.spawn(
            Transform(position=(2.0, 5.0, 0.0)), RigidBody(), Collider(shape=SPHERE, size=(0.2, 0.2, 0.2)),
            Joint(kind=BALL, other=made["top"], pivot=(0.0, 5.0, 0.0)),
        )  # fmt: skip

    _, seen = _watch(setup, 120, lambda: [made["bob"]])
    where = np.array([step[0][0] for step in seen])
    length = np.linalg.norm(where - (0.0, 5.0, 0.0), axis=1)
    assert np.abs(length - 2.0).max() < 0.01
    assert where[:, 0].min() < -1.0  # it swung through to the other side


def test_a_hinge_turns_about_its_axis_only_and_within_its_limits():
    made = {}

    def setup(world, dt):
        made["post"] = anchor(world, (0.0, 1.0, 0.0))
        made["door"] = world.spawn(
            Transform(position=(1.2, 1.0, 0.0)), RigidBody(), Collider(shape=BOX, size=(1.0, 1.0, 0.05), **NO_TOUCH),
            Joint(kind=HINGE, other=made["post"], pivot=(0.0, 1.0, 0.0), axis=(0.0, 1.0, 0.0), limits=(-0.6, 0.6)),
            AngularVelocity(angular=(0.0, 4.0, 0.0)),
        )  # fmt: skip

    _, seen = _watch(setup, 120, lambda: [made["door"]])
    rotation = np.array([step[0][1] for step in seen])
    assert np.abs(rotation[:, [0, 2]]).max() < 1e-3  # about y only
    angle = 2 * np.arctan2(rotation[:, 1], rotation[:, 3])
    assert angle.max() == pytest.approx(0.6, abs=0.06)  # it reached its limit and stopped there
    where = np.array([step[0][0] for step in seen])
    assert np.abs(np.linalg.norm(where[:, [0, 2]], axis=1) - 1.2).max() < 0.02  # 1.2 m from the axis
    assert np.abs(where[:, 1] - 1.0).max() < 0.01  # not sagging


def test_a_slider_moves_along_its_axis_only():
    made = {}

    def setup(world, dt):
        made["rail"] = anchor(world, (0.0, 3.0, 0.0))
        made["car"] = world.spawn(
            Transform(position=(0.0, 3.0, 0.0)), RigidBody(), Collider(shape=BOX, size=(0.3, 0.3, 0.3), **NO_TOUCH),
            Joint(kind=SLIDER, other=made["rail"], pivot=(0.0, 3.0, 0.0), axis=(0.6, -0.8, 0.0), limits=(-5.0, 2.0)),
        )  # fmt: skip

    _, seen = _watch(setup, 90, lambda: [made["car"]])
    where = np.array([step[0][0] for step in seen]) - (0.0, 3.0, 0.0)
    along = where @ np.array([0.6, -0.8, 0.0])
    across = where - along[:, None] * np.array([0.6, -0.8, 0.0])
    assert np.abs(across).max() < 0.01
    assert along.max() == pytest.approx(2.0, abs=0.05)  # gravity pulled it down the rail to its limit


def test_a_distance_joint_and_a_fixed_joint_keep_what_they_keep():
    made = {}

    def setup(world, dt):
        floor(world)
        made["top"] = anchor(world, (0.0, 6.0, 0.0))
        made["rope"] = world.spawn(
            Transform(position=(1.5, 6.0, 0.0)), RigidBody(), Collider(shape=SPHERE, size=(0.2, 0.2, 0.2)),
            Joint(kind=DISTANCE, other=made["top"], limits=(0.5, 2.0)),
        )  # fmt: skip
        made["a"] = world.spawn(Transform(position=(5.0, 2.0, 0.0)), RigidBody(), Collider(shape=BOX))
        made["b"] = world.spawn(
            Transform(position=(5.0, 3.0, 0.0)), RigidBody(), Collider(shape=BOX, **NO_TOUCH),
            Joint(kind=FIXED, other=made["a"]), AngularVelocity(angular=(3.0, 0.0, 1.0)),
        )  # fmt: skip

    _, seen = _watch(setup, 150, lambda: [made["rope"], made["a"], made["b"]])
    rope = np.array([step[0][0] for step in seen])
    apart = np.linalg.norm(rope - (0.0, 6.0, 0.0), axis=1)
    assert apart.max() < 2.0 + 0.02 and apart.max() > 1.9  # the rope went taut and held
    gap = np.array([np.linalg.norm(step[2][0] - step[1][0]) for step in seen])
    assert np.abs(gap - 1.0).max() < 0.02  # welded: the two boxes fell and tumbled as one


def refused(setup, capsys) -> str:
    """What a run of `setup` printed when it stopped with exit status 2 (one error)."""
    app = App(title="bad joint").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    with pytest.raises(SystemExit) as stop:
        app.run(frames=2)
    assert stop.value.code == 2
    return capsys.readouterr().err


def test_a_joint_to_an_entity_without_a_body_is_one_error_naming_them(capsys):
    def setup(world, dt):
        lost = world.spawn(Transform())
        world.spawn(Transform(), RigidBody(), Collider(), Joint(kind=BALL, other=lost))

    assert "which has no body" in refused(setup, capsys)


def test_a_joint_to_a_destroyed_entity_is_one_error_saying_so(capsys):
    def setup(world, dt):
        gone = world.spawn(Transform(), RigidBody(), Collider())
        world.destroy(gone)
        world.spawn(Transform(), RigidBody(), Collider(), Joint(kind=BALL, other=gone))

    err = refused(setup, capsys)
    assert "Joint.other" in err and "not alive" in err


def test_a_motor_turns_a_hinge_to_its_target_and_follows_a_new_one():
    from ecs_engine import Time

    made, angles = {}, {}

    def setup(world, dt):
        made["post"] = anchor(world, (0.0, 1.0, 0.0))
        made["door"] = world.spawn(
            Transform(position=(1.2, 1.0, 0.0)), RigidBody(), Collider(shape=BOX, size=(1.0, 1.0, 0.05), **NO_TOUCH),
            Joint(kind=HINGE, other=made["post"], pivot=(0.0, 1.0, 0.0), axis=(0.0, 1.0, 0.0), target=0.8),
        )  # fmt: skip

    def turn(world, dt):
        frame = world.resources[Time].steps
        q = world.get(made["door"], Transform).rotation
        angles[frame] = 2 * np.arctan2(q[1], q[3])
        if frame == 90:  # a system moves the target: the door follows
            world.set(made["door"], Joint, target=-0.5)

    app = App(title="motor").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", turn)
    app.run(frames=180)
    assert angles[90] == pytest.approx(0.8, abs=0.02)
    assert angles[180] == pytest.approx(-0.5, abs=0.02)


def test_a_motor_on_a_ball_joint_is_one_error(capsys):
    def setup(world, dt):
        top = anchor(world, (0.0, 5.0, 0.0))
        world.spawn(
            Transform(position=(1.0, 5.0, 0.0)),
            RigidBody(),
            Collider(shape=SPHERE),
            Joint(kind=BALL, other=top, target=1.0),
        )

    app = App(title="bad motor").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    with pytest.raises(SystemExit):
        app.run(frames=2)
    assert "a ball Joint has no motor" in capsys.readouterr().err
