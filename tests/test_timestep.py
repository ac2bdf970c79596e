"""Fixed-step simulation (accumulator, cap, interpolation) and orientations over long runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import ModelMatrix, PreviousTransform, Spring, Transform, Velocity
from ecs_engine.ecs.schedule import Schedule
from ecs_engine.ecs.timestep import FixedTimestep
from ecs_engine.maths.camera import yaw_pitch_quat
from ecs_engine.maths.transform import integrate_angular
from ecs_engine.systems import MotionSystem, SnapshotSystem, SpringSystem, TransformSystem
from ecs_engine.systems.camera_control import FlyInput, fly_step


def test_accumulator_steps_alpha_and_cap():
    clock = FixedTimestep(step=0.01, max_steps=4)
    assert [clock.advance(dt) for dt in (0.004, 0.004, 0.004, 0.025)] == [0, 0, 1, 2]
    assert clock.alpha == pytest.approx(0.7)
    assert clock.advance(10.0) == 4  # a ten-second hitch: four steps, the rest dropped
    assert clock.dropped_s == pytest.approx(10.0 - 0.04 + 0.007, abs=0.011)
    assert 0.0 <= clock.alpha < 1.0 and clock.steps == 7
    for bad in (-1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="finite and >= 0"):
            clock.advance(bad)
    with pytest.raises(ValueError, match="positive"):
        FixedTimestep(step=0.0)


def schedule() -> Schedule:
    s = Schedule(("fixed", "post_update"))
    s.add(SnapshotSystem(), "fixed")
    s.add(MotionSystem(), "fixed")
    s.add(SpringSystem("implicit"), "fixed")
    s.add(TransformSystem(), "post_update")
    return s


def test_a_hitch_of_seconds_does_not_explode_motion():
    world = World()
    mover = world.spawn(Transform(), Velocity(linear=(1.0, 0.0, 0.0)))
    stiff = world.spawn(
        Transform(position=(3.0, 0.0, 0.0)), Velocity(), Spring(anchor=(0.0, 0.0, 0.0), stiffness=1e5, damping=5.0)
    )
    clock = FixedTimestep(step=1 / 60, max_steps=8)
    s = schedule()
    assert s.run_frame(world, 5.0, clock) == 8
    assert world.get(mover, Transform).position[0] == pytest.approx(8 / 60)
    p = world.get(stiff, Transform).position
    assert np.isfinite(p).all() and abs(p[0]) < 3.0
    # and steady frames afterwards take one step each
    assert [s.run_frame(world, 1 / 60, clock) for _ in range(3)] == [1, 1, 1]


def test_rendering_interpolates_between_fixed_steps():
    world = World()
    smooth = world.spawn(Transform(), Velocity(linear=(1.0, 0.0, 0.0)), PreviousTransform(), ModelMatrix())
    stepped = world.spawn(Transform(), Velocity(linear=(1.0, 0.0, 0.0)), ModelMatrix())
    clock = FixedTimestep(step=0.1, max_steps=8)
    s = schedule()
    xs_smooth, xs_stepped = [], []
    for _ in range(12):  # frames of 0.025 s: four per step
        s.run_frame(world, 0.025, clock)
        xs_smooth.append(float(world.get(smooth, ModelMatrix).model[0, 3]))
        xs_stepped.append(float(world.get(stepped, ModelMatrix).model[0, 3]))
    # once the first step is taken (frame 4), the interpolated entity moves evenly: drawn one
    # step behind the simulation, between its last two states
    assert np.diff(xs_smooth)[3:] == pytest.approx(np.full(8, 0.025), abs=1e-6)
    assert sorted(set(np.round(np.diff(xs_stepped), 6))) == [0.0, 0.1]  # jumps once per step
    # interpolated: drawn between the last two steps, never ahead of the simulation
    assert xs_smooth[-1] <= world.get(smooth, Transform).position[0] + 1e-9


def test_without_the_snapshot_system_nothing_is_remembered():
    """The schedule knows no stock component: the snapshot is the stock system's job."""
    world = World()
    e = world.spawn(Transform(), Velocity(linear=(1.0, 0.0, 0.0)), PreviousTransform(), ModelMatrix())
    s = Schedule(("fixed", "post_update"))
    s.add(MotionSystem(), "fixed")
    s.run_frame(world, 0.25, FixedTimestep(step=0.1))
    assert world.get(e, PreviousTransform).position.tolist() == [0.0, 0.0, 0.0]
    assert world.get(e, Transform).position[0] == pytest.approx(0.2)


def test_million_rotation_steps_do_not_drift():
    """1e6 small rotations about a fixed axis, integrated step by step, against the exact
    rotation by the total angle."""
    axis = np.array([0.3, -0.8, 0.52])
    axis /= np.linalg.norm(axis)
    rate, dt, steps = 0.7, 1e-3, 1_000_000
    rotation = np.array([[0.0, 0.0, 0.0, 1.0]])
    angular = (axis * rate)[None, :]
    for _ in range(steps):
        integrate_angular(rotation, angular, dt)
    half = 0.5 * rate * dt * steps
    exact = np.array([*(axis * math.sin(half)), math.cos(half)])
    error = min(np.abs(rotation[0] - exact).max(), np.abs(rotation[0] + exact).max())
    assert error < 1e-6
    assert abs(np.linalg.norm(rotation[0]) - 1.0) < 1e-12


def test_fly_camera_orientation_is_rebuilt_not_integrated():
    """The fly camera's rotation is made from yaw and pitch each frame, so however many frames
    of input, it is exactly yaw_pitch_quat(yaw, pitch); pitch stays short of the poles."""
    yaw, pitch = np.zeros(1), np.zeros(1)
    position, rotation = np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]])
    speeds = np.ones(1), np.full(1, 2.0)
    for i in range(20_000):
        axes = FlyInput(turn=1.0, tilt=1.0 if (i // 500) % 2 == 0 else -1.0)
        fly_step(yaw, pitch, position, rotation, *speeds, axes, 1e-3)
    assert np.array_equal(rotation, yaw_pitch_quat(yaw, pitch))
    assert abs(np.linalg.norm(rotation) - 1.0) < 1e-15
    for _ in range(2000):  # hold "up": pitch stops short of straight up
        fly_step(yaw, pitch, position, rotation, *speeds, FlyInput(tilt=1.0), 1e-2)
    assert 0.5 * math.pi - 0.02 < pitch[0] < 0.5 * math.pi
