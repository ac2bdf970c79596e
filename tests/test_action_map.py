"""The ActionMap resource (systems/action_map.py): button and axis actions over keys, mouse and
gamepads, their edges, UI capture, rebinding and its refusals, and the bindings file (app/bindings.py):
saved and loaded, and a bad one is a warning and the defaults, the file left as it was."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from ecs_engine import World
from ecs_engine.app.bindings import bindings_file, load_bindings
from ecs_engine.systems import ActionMap, InputConfigError, InputState

DEFAULTS = {
    "fire": ["space", "mouse_left", "gamepad_a"],
    "turn": ["a/d", "gamepad_left_x"],
    "thrust": ["-gamepad_left_y"],
}


def fresh() -> tuple[ActionMap, InputState]:
    state = InputState()
    return ActionMap(DEFAULTS, input=state), state


def test_a_button_action_is_down_while_any_binding_is_held_with_its_own_edges():
    actions, s = fresh()
    s.press("space")
    assert actions.action_down("fire") and actions.action_pressed("fire") and not actions.action_released("fire")
    s.end_frame()
    s.press("mouse_left")  # a second binding while the first is held: no new press
    assert actions.action_down("fire") and not actions.action_pressed("fire")
    s.end_frame()
    s.release("space")  # one of two let go: still down, not released
    assert actions.action_down("fire") and not actions.action_released("fire")
    s.end_frame()
    s.release("mouse_left")
    assert not actions.action_down("fire") and actions.action_released("fire")
    s.end_frame()
    s.press("gamepad_a")
    s.release("gamepad_a")  # a tap between two frames: pressed and released, not down
    assert actions.action_pressed("fire") and actions.action_released("fire") and not actions.action_down("fire")


def test_an_axis_action_sums_a_key_pair_and_a_stick_clipped():
    actions, s = fresh()
    assert actions.axis("turn") == 0.0
    s.press("d")
    assert actions.axis("turn") == 1.0
    s.press("a")
    assert actions.axis("turn") == 0.0  # both keys cancel
    s.release("a")
    s.release("d")
    s.set_axis("gamepad_left_x", -0.5)
    assert actions.axis("turn") == pytest.approx(-(0.5 - 0.15) / 0.85)  # the dead zone applies
    s.press("a")
    assert actions.axis("turn") == -1.0  # clipped
    s.set_axis("gamepad_left_y", -1.0)  # stick up
    assert actions.axis("thrust") == 1.0  # reversed by the binding's '-'
    actions.dead_zone = 0.6
    assert actions.axis("thrust") == 1.0 and actions.axis("turn") == -1.0
    s.release("a")
    assert actions.axis("turn") == 0.0  # -0.5 is inside the map's own dead zone now


def test_the_ui_keeps_the_mouse_and_keyboard_it_has_but_not_the_gamepad():
    actions, s = fresh()
    s.pressed = {"mouse_left", "d"}
    s.mouse_captured_by_ui = True
    assert not actions.action_down("fire") and actions.axis("turn") == 1.0 and actions.pointer() is None
    s.mouse_captured_by_ui, s.keyboard_captured_by_ui = False, True
    assert actions.action_down("fire") and actions.axis("turn") == 0.0 and actions.pointer() == (0.0, 0.0)
    s.pressed, s.mouse_captured_by_ui = {"gamepad_a"}, True
    s.set_axis("gamepad_left_x", 1.0)
    assert actions.action_down("fire") and actions.axis("turn") == 1.0


def test_rebinding_at_run_time_and_its_refusals_change_nothing():
    actions, s = fresh()
    actions.bind("fire", "left_control", "gamepad_right_bumper")
    s.press("space")
    assert not actions.action_down("fire")
    s.press("left_control")
    assert actions.action_down("fire") and actions.bound("fire") == ["left_control", "gamepad_right_bumper"]
    for args, message in (
        (("fire", "spcae"), r"unknown key, button or axis 'spcae'; did you mean space"),
        (("fire", "gamepad_left_x"), r"'fire' is a button action: bind keys and buttons"),
        (("turn", "space"), r"'turn' is an axis action: bind axes or button pairs like 'a/d'"),
        (("turn", "a/"), r"a button pair is written 'minus/plus'"),
        (("turn", "-a"), r"only an axis can be reversed"),
        (("jump", "space", "gamepad_left_x"), r"mixes buttons and axes"),
        (("", "space"), r"an action name is a non-empty string"),
    ):
        with pytest.raises(ValueError, match=message):
            actions.bind(*args)
    assert actions.bound("fire") == ["left_control", "gamepad_right_bumper"] and "jump" not in actions.bindings
    with pytest.raises(ValueError, match="unknown action 'fier'; did you mean fire"):
        actions.action_down("fier")
    with pytest.raises(ValueError, match="'fire' is a button action: use action_down"):
        actions.axis("fire")
    with pytest.raises(ValueError, match="'turn' is an axis action: use axis"):
        actions.action_pressed("turn")
    actions.bind("fire")  # unbound: never down
    assert not actions.action_down("fire")


def test_of_world_reads_the_worlds_input():
    world = World()
    with pytest.raises(KeyError, match="no ActionMap resource"):
        ActionMap.of(world)
    world.resources[ActionMap] = ActionMap(DEFAULTS)
    state = world.resources[InputState] = InputState(pressed={"space"})
    assert ActionMap.of(world).input is state and ActionMap.of(world).action_down("fire")


def test_bindings_save_and_load_over_the_defaults(tmp_path):
    actions, _ = fresh()
    actions.bind("fire", "f")
    actions.dead_zone = 0.25
    path = tmp_path / "sub" / "input.json"
    actions.save(path)
    assert json.loads(path.read_text())["actions"]["fire"] == ["f"]
    loaded = ActionMap.load(path, DEFAULTS)
    assert loaded.bound("fire") == ["f"] and loaded.bound("turn") == ["a/d", "gamepad_left_x"]
    assert loaded.dead_zone == 0.25
    path.write_text('{"version": 1, "actions": {"turn": ["left/right"]}}')  # only some actions
    loaded = ActionMap.load(path, DEFAULTS)
    assert loaded.bound("turn") == ["left/right"] and loaded.bound("fire") == DEFAULTS["fire"]
    assert ActionMap.load(tmp_path / "none.json", DEFAULTS).bound("fire") == DEFAULTS["fire"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('{"version": 1, "actions": {"fire": ["spcae"]}}', r"action 'fire': unknown key, .*did you mean space"),
        ('{"version": 1, "actions": {"fier": ["space"]}}', r"unknown action 'fier'; did you mean fire"),
        ('{"version": 1, "actions": {"turn": ["space"]}}', r"'turn' is an axis action: bind axes"),
        ('{"version": 1, "actions": {"fire": "space"}}', r"action 'fire': expected a list of bindings"),
        ('{"version": 1, "actions": {"fire": [3]}}', r"action 'fire': a binding is a string"),
        ('{"version": 1, "actions": []}', r'"actions" must be an object'),
        ('{"version": 2, "actions": {}}', r"version 2 is not 1"),
        ('{"version": 1, "action": {}}', r"unknown key 'action'; did you mean actions"),
        ('{"version": 1, "dead_zone": 1.5}', r"dead_zone must be a number from 0"),
        ('{"version": 1, "dead_zone": true}', r"dead_zone must be a number from 0"),
        ("[1, 2]", r"expected an object"),
        ('{"version": 1, "actions": {', r"not JSON \(Expecting"),
        (b"\xff\xfe{", r"not UTF-8 text"),
        # issue 34 #9: these ended in a RecursionError, a game that stopped, or were accepted
        ("[" * 100000 + "]" * 100000, r"nested too deeply"),
        ('{"version": 1, "dead_zone": 1' + "0" * 5000 + "}", r"an integer of 5001 digits"),
        ('{"version": 1, "dead_zone": 1e999}', r"the number 1e999 is too large"),
        ('{"version": true, "actions": {}}', r"version True is not 1"),
        ('{"version": 1.0, "actions": {}}', r"version 1\.0 is not 1"),
    ],
)
def test_a_bad_bindings_file_is_one_error_naming_it(tmp_path, text, message):
    path = tmp_path / "input.json"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    with pytest.raises(InputConfigError, match=f"input bindings {path}: {message}"):
        ActionMap.load(path, DEFAULTS)


def test_a_bad_user_file_is_a_warning_and_the_defaults_and_stays_as_it_was(config_home):
    assert bindings_file("asteroids") == config_home / "ecs_engine" / "input-asteroids.json"
    assert bindings_file() == config_home / "ecs_engine" / "input.json"
    path = bindings_file("asteroids")
    path.parent.mkdir(parents=True)
    path.write_text('{"version": 1, "actions": {"fire": ["spcae"]}}')
    said: list[str] = []
    actions = load_bindings(DEFAULTS, "asteroids", warn=said.append)
    assert actions.bound("fire") == DEFAULTS["fire"]
    assert len(said) == 1 and "did you mean space" in said[0] and "default bindings" in said[0]
    assert path.read_text() == '{"version": 1, "actions": {"fire": ["spcae"]}}'
    path.write_text('{"version": 1, "actions": {"fire": ["f"]}}')
    assert load_bindings(DEFAULTS, "asteroids", warn=said.append).bound("fire") == ["f"] and len(said) == 1


@pytest.mark.parametrize(
    "text", ["[" * 100000, '{"version": 1, "dead_zone": 1' + "0" * 5000 + "}", '{"version": true, "actions": {}}']
)
def test_a_hostile_user_file_is_a_warning_and_the_defaults(config_home, text):
    """docs/input.md's promise, kept for hostile files too (issue 34 #9): one warning naming the file."""
    path = bindings_file("asteroids")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    said: list[str] = []
    actions = load_bindings(DEFAULTS, "asteroids", warn=said.append)
    assert actions.bound("fire") == DEFAULTS["fire"]
    assert len(said) == 1 and str(path) in said[0] and "playing with the default bindings" in said[0]


def test_play_with_a_bad_bindings_file_warns_once_and_plays(config_home):
    path = bindings_file("asteroids")
    path.parent.mkdir(parents=True)
    path.write_text("{not json")
    env = dict(os.environ)
    env.pop("DISPLAY", None)
    run = subprocess.run(
        [sys.executable, "-m", "ecs_engine", "play", "asteroids", "--headless", "--frames", "3"]
        + ["--width", "96", "--height", "64"],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    assert run.stderr.count("warning: input bindings") == 1 and "not JSON" in run.stderr
    assert "Traceback" not in run.stderr and path.read_text() == "{not json"
