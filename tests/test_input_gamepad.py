"""Gamepads (app/gamepads.py) without a gamepad: fake `glfw.get_gamepad_state` results go through
the same reading and polling as real ones; buttons get the keys' down / pressed / released
semantics, axes a dead zone, and a pad that goes away releases what it held."""

from __future__ import annotations

from types import SimpleNamespace

import glfw
import pytest

from ecs_engine.app.gamepads import GamepadPoller, read_gamepads, reading
from ecs_engine.systems import InputState
from ecs_engine.systems.input_state import dead_zoned, gamepad_axes, gamepad_buttons


def raw(buttons=(), **axes):
    """A get_gamepad_state result: 15 buttons (0/1), 6 axes (triggers resting at -1)."""
    values = [0] * 15
    for name in buttons:
        values[gamepad_buttons().index(name)] = 1
    levels = [0.0, 0.0, 0.0, 0.0, -1.0, -1.0]
    for name, value in axes.items():
        levels[gamepad_axes().index("gamepad_" + name)] = value
    return (values, levels)


def fake_glfw(pads: dict[int, tuple]) -> SimpleNamespace:
    """The few GLFW joystick calls the poller makes, answering for `pads` (joystick id -> raw)."""
    return SimpleNamespace(
        JOYSTICK_1=glfw.JOYSTICK_1,
        JOYSTICK_LAST=glfw.JOYSTICK_LAST,
        joystick_is_gamepad=lambda jid: jid in pads,
        get_gamepad_state=lambda jid: pads.get(jid),
        get_gamepad_name=lambda jid: f"pad {jid}",
    )


def test_the_names_follow_glfws_standard_mapping():
    assert gamepad_buttons()[glfw.GAMEPAD_BUTTON_A] == "gamepad_a"
    assert gamepad_buttons()[glfw.GAMEPAD_BUTTON_DPAD_UP] == "gamepad_dpad_up"
    assert gamepad_buttons()[glfw.GAMEPAD_BUTTON_LEFT_BUMPER] == "gamepad_left_bumper"
    assert len(gamepad_buttons()) == glfw.GAMEPAD_BUTTON_LAST + 1
    assert gamepad_axes()[glfw.GAMEPAD_AXIS_LEFT_X] == "gamepad_left_x"
    assert gamepad_axes()[glfw.GAMEPAD_AXIS_RIGHT_TRIGGER] == "gamepad_right_trigger"
    assert InputState.check("gamepad_start") == "gamepad_start"  # checked like keys
    with pytest.raises(ValueError, match="did you mean gamepad_a"):
        InputState.check("gamepad_aa")
    with pytest.raises(ValueError, match=r"unknown gamepad axis 'gamepad_left'; did you mean .*gamepad_left_x"):
        InputState().axis("gamepad_left")


def test_a_reading_names_buttons_and_moves_triggers_to_0_1():
    pad = reading(raw(("gamepad_a", "gamepad_dpad_up"), left_x=-0.5, right_trigger=1.0), "pad")
    assert pad.pressed == {"gamepad_a", "gamepad_dpad_up"}
    assert pad.axes["gamepad_left_x"] == -0.5 and pad.axes["gamepad_right_trigger"] == 1.0
    assert pad.axes["gamepad_left_trigger"] == 0.0  # at rest


def test_buttons_go_down_and_up_like_keys_and_a_lost_pad_releases_them():
    state, poller = InputState(), GamepadPoller()
    frames = [
        {0: raw(("gamepad_a",))},  # pad 0 presses A
        {0: raw(("gamepad_a",)), 1: raw(("gamepad_a", "gamepad_b"))},  # pad 1 joins, also holds A
        {1: raw(("gamepad_a", "gamepad_b"))},  # pad 0 unplugged: A is still held by pad 1
        {},  # pad 1 unplugged too
    ]
    seen = []
    for pads in frames:
        poller.poll(fake_glfw(pads), state)
        seen.append((sorted(state.pressed), sorted(state.just_pressed), sorted(state.just_released)))
        state.end_frame()
    assert seen[0] == (["gamepad_a"], ["gamepad_a"], [])
    assert seen[1] == (["gamepad_a", "gamepad_b"], ["gamepad_b"], [])
    assert seen[2] == (["gamepad_a", "gamepad_b"], [], [])
    assert seen[3] == ([], [], ["gamepad_a", "gamepad_b"])
    assert state.gamepads == {}


def test_axes_take_a_dead_zone_and_return_to_rest_when_the_pad_goes():
    state, poller = InputState(), GamepadPoller()
    poller.poll(fake_glfw({2: raw(left_x=0.1, left_y=-1.0, right_trigger=0.0)}), state)
    assert state.gamepads[2].name == "pad 2"
    assert state.axes["gamepad_left_x"] == pytest.approx(0.1) and state.axis("gamepad_left_x") == 0.0
    assert state.axis("gamepad_left_y") == -1.0
    assert state.axis("gamepad_right_trigger") == pytest.approx((0.5 - 0.15) / 0.85)
    assert state.axis("gamepad_left_x", dead_zone=0.05) == pytest.approx((0.1 - 0.05) / 0.95)
    state.dead_zone = 0.0
    assert state.axis("gamepad_left_x") == pytest.approx(0.1)
    poller.poll(fake_glfw({}), state)
    assert all(state.axis(name) == 0.0 for name in gamepad_axes())


def test_a_scripted_axis_stays_until_a_pad_moves_it():
    """The window polls every frame; a value an input script set is not overwritten by a pad
    that did not move."""
    state, poller = InputState(), GamepadPoller()
    state.set_axis("gamepad_left_x", 0.75)
    poller.poll(fake_glfw({}), state)
    assert state.axes["gamepad_left_x"] == 0.75
    poller.poll(fake_glfw({0: raw(left_x=-0.25)}), state)
    assert state.axes["gamepad_left_x"] == -0.25


def test_no_gamepad_reads_as_none():
    assert read_gamepads(fake_glfw({})) == {}
    vanished = fake_glfw({})
    vanished.joystick_is_gamepad = lambda jid: jid == 3  # gone before its state was read
    assert read_gamepads(vanished) == {}


@pytest.mark.parametrize(("value", "want"), [(0.0, 0.0), (0.15, 0.0), (-0.15, 0.0), (1.0, 1.0), (-1.0, -1.0)])
def test_the_dead_zone_keeps_the_ends(value, want):
    assert dead_zoned(value, 0.15) == want
