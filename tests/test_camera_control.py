"""Fly camera: every key of the map turns or moves the right way, dt scaling, normalised
diagonals, the pitch clamp, yaw wrapping, UI keyboard capture, and no drift over 1e6 frames."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import Schedule, World
from ecs_engine.components import ActiveCamera, FlyCamera
from ecs_engine.components.camera import Camera
from ecs_engine.components.transform import Transform
from ecs_engine.maths.camera import yaw_pitch_quat
from ecs_engine.maths.transform import quat_to_mat3
from ecs_engine.systems.camera_control import (
    KEYS,
    PITCH_LIMIT,
    FlyCameraSystem,
    FlyInput,
    InputState,
    fly_input,
    fly_step,
    wrap_angle,
)

SPEED, TURN, DT = 2.0, 1.0, 0.25


def make_world(yaw=0.0, pitch=0.0, position=(0.0, 0.0, 0.0)):
    w = World()
    cam = w.spawn(
        Camera(),
        ActiveCamera(),
        Transform(position=position),
        FlyCamera(yaw=yaw, pitch=pitch, move_speed=SPEED, turn_speed=TURN),
    )
    schedule = Schedule()
    schedule.add(FlyCameraSystem())
    return w, cam, schedule


def press(w, schedule, keys, frames=1, dt=DT, **flags):
    w.resources[InputState] = InputState(set(keys), **flags)
    for _ in range(frames):
        schedule.run(w, dt)


def view_dir(w, cam):
    q = w.get(cam, Transform).rotation
    return quat_to_mat3(q[None])[0] @ np.array([0.0, 0.0, -1.0])


def position(w, cam):
    return w.get(cam, Transform).position


# ------------------------------------------------------------------------ movement keys
@pytest.mark.parametrize(
    "key, expected",
    [("w", (0, 0, -1)), ("s", (0, 0, 1)), ("a", (-1, 0, 0)), ("d", (1, 0, 0)), ("e", (0, 1, 0)), ("q", (0, -1, 0))],
)
def test_each_move_key_at_yaw_0(key, expected):
    w, cam, schedule = make_world(position=(10.0, 20.0, 30.0))
    press(w, schedule, {key})
    step = SPEED * DT
    assert np.allclose(position(w, cam), np.array([10.0, 20.0, 30.0]) + step * np.array(expected), atol=1e-12)
    assert w.get(cam, FlyCamera).yaw == 0.0 and w.get(cam, FlyCamera).pitch == 0.0


def test_moves_follow_the_view_direction():
    w, cam, schedule = make_world(yaw=math.pi / 2)  # looking toward -X
    press(w, schedule, {"w"})
    assert np.allclose(position(w, cam), [-SPEED * DT, 0, 0], atol=1e-12)
    w, cam, schedule = make_world(yaw=math.pi / 2)
    press(w, schedule, {"d"})  # right of -X is -Z
    assert np.allclose(position(w, cam), [0, 0, -SPEED * DT], atol=1e-12)
    w, cam, schedule = make_world(pitch=0.5)  # W flies along the pitched view, E stays world-up
    press(w, schedule, {"w"})
    assert np.allclose(position(w, cam), SPEED * DT * np.array([0, math.sin(0.5), -math.cos(0.5)]))
    w, cam, schedule = make_world(yaw=0.3, pitch=0.5)
    press(w, schedule, {"e"})
    assert np.allclose(position(w, cam), [0, SPEED * DT, 0], atol=1e-12)


def test_diagonals_are_normalised_and_opposite_keys_cancel():
    for keys in ({"w", "d"}, {"w", "a", "e"}, {"s", "d", "q"}, {"w", "e"}):
        w, cam, schedule = make_world(yaw=0.4)
        press(w, schedule, keys)
        assert np.linalg.norm(position(w, cam)) == pytest.approx(SPEED * DT, rel=1e-12)
    w, cam, schedule = make_world()
    press(w, schedule, {"w", "d"})
    assert np.allclose(position(w, cam), SPEED * DT * np.array([1, 0, -1]) / math.sqrt(2))
    w, cam, schedule = make_world()
    press(w, schedule, {"w", "s", "a", "d", "e", "q"})
    assert position(w, cam).tolist() == [0.0, 0.0, 0.0]


def test_movement_scales_with_dt():
    w1, c1, s1 = make_world(yaw=1.0)
    press(w1, s1, {"w", "d"}, frames=4, dt=0.05)
    w2, c2, s2 = make_world(yaw=1.0)
    press(w2, s2, {"w", "d"}, frames=1, dt=0.2)
    assert np.allclose(position(w1, c1), position(w2, c2), atol=1e-12)
    assert np.linalg.norm(position(w2, c2)) == pytest.approx(SPEED * 0.2)


# ------------------------------------------------------------------------ turning keys
def test_left_yaws_counter_clockwise_seen_from_above():
    w, cam, schedule = make_world()
    press(w, schedule, {"left"})
    fly = w.get(cam, FlyCamera)
    assert fly.yaw == pytest.approx(TURN * DT)
    d = view_dir(w, cam)
    assert d[0] < 0 and d[2] < 0 and d[1] == pytest.approx(0, abs=1e-15)  # from -Z toward -X
    assert np.allclose(d, [-math.sin(TURN * DT), 0, -math.cos(TURN * DT)])
    # counter-clockwise from above: the cross product (old x new) points to +Y
    assert np.cross([0, 0, -1], d)[1] > 0


def test_right_yaws_clockwise():
    w, cam, schedule = make_world()
    press(w, schedule, {"right"})
    assert w.get(cam, FlyCamera).yaw == pytest.approx(-TURN * DT)
    d = view_dir(w, cam)
    assert d[0] > 0 and np.cross([0, 0, -1], d)[1] < 0


def test_up_and_down_pitch():
    w, cam, schedule = make_world()
    press(w, schedule, {"up"})
    assert w.get(cam, FlyCamera).pitch == pytest.approx(TURN * DT)
    assert view_dir(w, cam)[1] == pytest.approx(math.sin(TURN * DT))
    w, cam, schedule = make_world()
    press(w, schedule, {"down"})
    assert w.get(cam, FlyCamera).pitch == pytest.approx(-TURN * DT)
    assert view_dir(w, cam)[1] < 0


def test_turning_does_not_move_and_rotation_matches_yaw_pitch():
    w, cam, schedule = make_world(position=(1.0, 2.0, 3.0))
    press(w, schedule, {"left", "up"}, frames=3)
    fly = w.get(cam, FlyCamera)
    assert position(w, cam).tolist() == [1.0, 2.0, 3.0]
    assert np.array_equal(w.get(cam, Transform).rotation, yaw_pitch_quat(fly.yaw, fly.pitch))


def test_pitch_is_clamped_short_of_the_poles_and_the_view_never_flips():
    for key, sign in (("up", 1.0), ("down", -1.0)):
        w, cam, schedule = make_world(yaw=0.2)
        press(w, schedule, {key}, frames=20)  # 5 rad of input
        assert w.get(cam, FlyCamera).pitch == sign * PITCH_LIMIT
        d = view_dir(w, cam)
        horizontal = np.array([-math.sin(0.2), 0, -math.cos(0.2)])
        assert np.dot(d, horizontal) > 0  # still facing the yaw direction, not flipped over
        assert sign * d[1] < 1.0
    assert PITCH_LIMIT == pytest.approx(math.pi / 2 - 0.01)
    w, cam, schedule = make_world(pitch=3.0)  # set out of range: clamped on the next frame
    press(w, schedule, set())
    assert w.get(cam, FlyCamera).pitch == PITCH_LIMIT


def test_yaw_wraps_to_minus_pi_pi():
    assert wrap_angle(np.array(math.pi)) == math.pi
    assert wrap_angle(np.array(-math.pi)) == math.pi
    assert wrap_angle(np.array(0.0)) == 0.0
    assert wrap_angle(np.array(3 * math.pi + 0.5)) == pytest.approx(-math.pi + 0.5)
    w, cam, schedule = make_world(yaw=3.0)
    press(w, schedule, {"left"})  # 3.25 rad -> wraps
    yaw = w.get(cam, FlyCamera).yaw
    assert yaw == pytest.approx(3.25 - 2 * math.pi)
    assert -math.pi < yaw <= math.pi


# ---------------------------------------------------------------------------- input state
def test_keyboard_captured_by_ui_freezes_the_camera():
    w, cam, schedule = make_world(yaw=0.3, position=(1.0, 1.0, 1.0))
    before = w.get(cam, Transform).rotation
    press(w, schedule, KEYS, frames=3, keyboard_captured_by_ui=True)
    fly = w.get(cam, FlyCamera)
    assert position(w, cam).tolist() == [1.0, 1.0, 1.0]
    assert (fly.yaw, fly.pitch) == (0.3, 0.0)
    assert np.allclose(w.get(cam, Transform).rotation, yaw_pitch_quat(0.3, 0.0))
    assert not np.array_equal(before, w.get(cam, Transform).rotation)  # rebuilt from yaw anyway


def test_mouse_capture_does_not_block_keys_and_no_resource_means_no_input():
    w, cam, schedule = make_world()
    press(w, schedule, {"w"}, mouse_captured_by_ui=True)
    assert position(w, cam)[2] < 0
    w, cam, schedule = make_world()
    schedule.run(w, DT)  # no InputState resource at all
    assert position(w, cam).tolist() == [0.0, 0.0, 0.0]


def test_fly_input_axes_and_unknown_keys():
    assert fly_input(None) == FlyInput()
    assert fly_input(InputState({"w", "left", "e", "space", "W"})) == FlyInput(1.0, 0.0, 1.0, 0.0, 1.0)
    assert fly_input(InputState({"s", "right", "down", "a", "q"})) == FlyInput(-1.0, -1.0, -1.0, -1.0, -1.0)
    assert fly_input(InputState({"w"}, keyboard_captured_by_ui=True)) == FlyInput()


def test_system_declares_access_and_component_checks():
    s = FlyCameraSystem()
    assert s.writes == frozenset({Transform, FlyCamera})
    w = World()
    cam = w.spawn(FlyCamera())
    assert w.has(cam, Transform)  # FlyCamera brings a Transform
    for bad in (dict(move_speed=0.0), dict(turn_speed=-1.0), dict(yaw=math.nan), dict(pitch=math.inf)):
        with pytest.raises(ValueError):
            w.spawn(FlyCamera(**bad))


# ----------------------------------------------------------------------------- no drift
def test_a_million_frames_of_small_input_never_drift():
    """1e6 camera-frames: 100 cameras x 10,000 sequential frames through fly_step, random small
    yaw/pitch input each frame (biased so yaw wraps many times and pitch hits its clamp)."""
    rng = np.random.default_rng(3)
    n, frames, dt = 100, 10_000, 1.0 / 60.0
    yaw = rng.uniform(-math.pi, math.pi, n)
    pitch = rng.uniform(-1.0, 1.0, n)
    pos = np.zeros((n, 3))
    rot = yaw_pitch_quat(yaw, pitch)
    move_speed = np.full(n, 3.0)
    turn_speed = rng.uniform(0.5, 3.0, n)
    bias = rng.choice([-0.4, 0.4], size=(n, 2))
    for frame in range(frames):
        turn = np.clip(np.round(rng.normal(bias[:, 0], 1.0)), -1, 1)
        tilt = np.clip(np.round(rng.normal(bias[:, 1], 1.0)), -1, 1)
        fly_step(yaw, pitch, pos, rot, move_speed, turn_speed, FlyInput(turn, tilt), dt)
        if frame % 1000 == 999:
            assert np.abs(np.linalg.norm(rot, axis=1) - 1.0).max() <= 1e-6
    assert np.array_equal(rot, yaw_pitch_quat(yaw, pitch))
    assert np.abs(np.linalg.norm(rot, axis=1) - 1.0).max() <= 1e-6
    assert ((yaw > -math.pi) & (yaw <= math.pi)).all()
    assert (np.abs(pitch) <= PITCH_LIMIT).all()
    assert (np.abs(pitch) == PITCH_LIMIT).any()  # the clamp was exercised
    assert pos.tolist() == np.zeros((n, 3)).tolist()  # turning alone never moves


def test_yaw_pitch_quat_unit_for_a_million_angles():
    rng = np.random.default_rng(4)
    yaw = rng.uniform(-math.pi, math.pi, 1_000_000)
    pitch = rng.uniform(-PITCH_LIMIT, PITCH_LIMIT, 1_000_000)
    q = yaw_pitch_quat(yaw, pitch)
    assert np.abs(np.einsum("ij,ij->i", q, q) - 1.0).max() <= 1e-12
