"""`ecs-engine play asteroids`: headless with the bot it exits 0 and prints the score, the same
on every run; keys drive the ship through the window's input; the HUD's Restart button restarts
after game over; bad arguments are one clear error."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.demos.asteroids_controls import ACTIONS, ShipControlSystem
from ecs_engine.demos.asteroids_game import ShipControls
from ecs_engine.systems import ActionMap, InputState


def play(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env.pop("DISPLAY", None)
    return subprocess.run(
        [sys.executable, "-m", "ecs_engine", "play", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )


def test_headless_autoplay_exits_0_and_prints_the_same_score_and_sound_every_run(tmp_path):
    size = ("--width", "96", "--height", "64")
    runs = [
        play("asteroids", "--headless", "--autoplay", "--frames", "600", "--seed", "1", *size, "--audio-out", str(wav))
        for wav in (tmp_path / "a.wav", tmp_path / "b.wav")
    ]
    for run in runs:
        assert run.returncode == 0, run.stderr
    lines = [next(line for line in r.stdout.splitlines() if line.startswith("asteroids: score")) for r in runs]
    assert lines[0] == lines[1]
    assert int(lines[0].split()[2]) > 0  # the bot scored
    sound = (tmp_path / "a.wav").read_bytes()
    assert sound == (tmp_path / "b.wav").read_bytes() and len(sound) == 44 + 600 * 800 * 8  # 600 frames of 1/60 s


def test_bad_arguments_are_one_clear_error():
    for args, message in (
        (("chess", "--headless"), "invalid choice: 'chess'"),
        (("asteroids", "--headless", "--level", "0"), "expected a number above 0"),
        (("asteroids", "--headless", "--entities", "5"), "--entities sizes the scaling"),
        (("asteroids", "--headless", "--level", "99"), "--level 99: asteroids has levels 1 to 6"),
        (("asteroids", "--headless", "--seed", "-1"), "argument --seed: expected a number of 0 or more, got -1"),
    ):
        run = play(*args)
        assert run.returncode == 2 and message in run.stderr and "Traceback" not in run.stderr, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1, run.stderr


def test_the_frames_help_says_what_a_headless_run_does(monkeypatch, capsys):
    """Each command's --frames help gives the frame count its --headless run has without
    --frames (play's is not demo's)."""
    import re

    import ecs_engine.app.loop as loop
    from ecs_engine.app import cli
    from ecs_engine.app.report import RunResult

    ran = []
    monkeypatch.setattr(loop, "run", lambda options, *args, **kwargs: ran.append(options.frames) or RunResult())
    monkeypatch.setenv("COLUMNS", "300")  # the help on one line
    for command in ("play", "demo"):
        with pytest.raises(SystemExit):
            cli.main([command, "--help"])
        said = int(re.search(r"headless: (\d+)", capsys.readouterr().out).group(1))
        assert cli.main([command, "asteroids" if command == "play" else "cube", "--headless"]) == 0
        if command == "play":
            assert ran.pop() == said == 600
        else:
            assert said == 1 and ran.pop() is None  # None: the offscreen source's one frame


def test_the_score_is_printed_even_when_the_screenshot_cannot_be_written(tmp_path, monkeypatch, capsys):
    import ecs_engine.app.loop as loop
    from ecs_engine.app import cli
    from ecs_engine.errors import UsageError

    def full(pixels, path):
        raise UsageError(f"cannot write {path}: No space left on device")

    monkeypatch.setattr(loop, "save_png", full)
    shot = tmp_path / "shot.png"
    args = ["play", "asteroids", "--headless", "--autoplay", "--frames", "3", "--width", "64", "--height", "48"]
    assert cli.main([*args, "--screenshot", str(shot), "--threads", "2"]) == 2
    out, err = capsys.readouterr()
    assert "asteroids: score" in out and "world " in out, out  # the run's result is not lost
    assert err.strip() == f"ecs-engine: error: cannot write {shot}: No space left on device"


def test_keys_and_buttons_become_ship_controls_unless_the_ui_has_them():
    """Through the game's actions: keys while the UI does not have the keyboard, mouse buttons
    while it does not have the mouse, gamepads always."""
    world = World()
    controls = world.resources[ShipControls] = ShipControls()
    world.resources[ActionMap] = ActionMap(ACTIONS)
    keys = world.resources[InputState] = InputState(pressed={"left", "w", "space"})
    system = ShipControlSystem()
    world.run_system(system, 0.0)
    assert (controls.turn, controls.thrust, controls.fire, controls.restart) == (1.0, 1.0, True, False)
    keys.pressed = {"d", "down", "r"}
    world.run_system(system, 0.0)
    assert (controls.turn, controls.thrust, controls.fire, controls.restart) == (-1.0, -1.0, False, True)
    keys.pressed = set()
    world.run_system(system, 0.0)
    assert controls.restart  # a latch until the restart system takes it
    keys.pressed, keys.keyboard_captured_by_ui = {"left", "w", "space"}, True
    world.run_system(system, 0.0)
    assert (controls.turn, controls.thrust, controls.fire) == (0.0, 0.0, False)
    keys.pressed, keys.keyboard_captured_by_ui, keys.mouse_captured_by_ui = {"mouse_left"}, False, True
    world.run_system(system, 0.0)
    assert not controls.fire  # the click went to the UI
    keys.mouse_captured_by_ui = False
    world.run_system(system, 0.0)
    assert controls.fire
    keys.pressed, keys.keyboard_captured_by_ui, keys.mouse_captured_by_ui = {"gamepad_a"}, True, True
    world.run_system(system, 0.0)
    assert controls.fire  # the UI takes neither the pad's buttons ...
    keys.set_axis("gamepad_left_x", 1.0)
    world.run_system(system, 0.0)
    assert controls.turn == -1.0  # ... nor its sticks


def test_the_hud_restarts_the_game_after_game_over():
    """Headless: the HUD shows game over with a Restart button; a click on it starts a new game."""
    from imgui_bundle import imgui

    from ecs_engine.app.app_session import AppSession, AppUI
    from ecs_engine.app.game_module import game_app
    from ecs_engine.app.offscreen import OffscreenSource
    from ecs_engine.app.perf import PerfMonitor
    from ecs_engine.app.settings import RunOptions
    from ecs_engine.demos.asteroids_game import Game

    source = OffscreenSource()
    options = RunOptions(scene="cube", width=320, height=240, threads=2, validate=True)
    session = AppSession(game_app("asteroids"), options, source)
    ui = AppUI(session, None)
    perf = PerfMonitor()
    try:
        game = session.world.resources[Game]
        game.over, game.health = True, 0.0
        io = imgui.get_io()

        def frame(mouse=None, down=None):
            if mouse is not None:
                io.add_mouse_pos_event(*mouse)
            if down is not None:
                io.add_mouse_button_event(0, down)
            session.schedule.run(session.world, 1 / 60)
            ui.build(session.world, None, perf, 1 / 60, 320, 240)
            session.renderer.render(session.world, readback=True)

        frame()
        frame()
        x0, y0, x1, y1 = ui.rects["restart"]
        frame(mouse=((x0 + x1) / 2, (y0 + y1) / 2))
        frame(down=True)
        frame(down=False)
        frame()
        game = session.world.resources[Game]
        assert not game.over and game.health == 100.0 and game.score == 0
    finally:
        ui.destroy()
        session.close()
    assert source.validation_messages() == []


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_the_windowed_game_takes_keys_and_restarts_from_the_hud():
    """In a window under Xvfb: space and W go through the window's key path (apply_key) and the
    ship fires; after game over R starts a new game."""
    import glfw as glfw_module

    from ecs_engine.app.app_session import AppSession, AppUI
    from ecs_engine.app.game_module import game_app
    from ecs_engine.app.loop import run
    from ecs_engine.app.settings import RunOptions
    from ecs_engine.app.window import WindowSource, apply_key, key_names, open_glfw
    from ecs_engine.components import Transform
    from ecs_engine.demos.asteroids_game import Game, Ship

    glfw = open_glfw()
    assert glfw is not None
    holder: dict = {}
    names = key_names(glfw_module)

    def script(frame, glfw_, window):
        source, session = holder["source"], holder.get("session")
        if frame == 2:
            apply_key(glfw_, names, source.input, glfw_.KEY_SPACE, glfw_.PRESS)
            apply_key(glfw_, names, source.input, glfw_.KEY_W, glfw_.PRESS)
        if frame == 20:
            apply_key(glfw_, names, source.input, glfw_.KEY_SPACE, glfw_.RELEASE)
            apply_key(glfw_, names, source.input, glfw_.KEY_W, glfw_.RELEASE)
            game = session.world.resources[Game]
            holder["shots"], game.health = game.shots, 0.0
            game.over = True
        if frame == 24:
            apply_key(glfw_, names, source.input, glfw_.KEY_R, glfw_.PRESS)
        if frame == 26:
            apply_key(glfw_, names, source.input, glfw_.KEY_R, glfw_.RELEASE)

    def make(options, source):
        holder["session"] = AppSession(game_app("asteroids"), options, source)
        return holder["session"]

    def ui(session, window):
        holder["ui"] = AppUI(session, window)
        return holder["ui"]

    source = holder["source"] = WindowSource(glfw, on_frame=script)
    options = RunOptions(scene="cube", width=320, height=240, frames=36, validate=True, quiet=True, headless=False)
    result = run(options, source, make_session=make, ui=ui)
    assert result.validation_messages == [] and result.frames == 36
    world = holder["session"].world
    game = world.resources[Game]
    assert holder["shots"] > 0  # space fired
    assert not game.over and game.health == 100.0  # restarted by R
    ship = world.query(Ship).entities()
    assert len(ship) == 1 and np.allclose(world.get(int(ship[0]), Transform).position, 0.0, atol=0.5)


def test_the_hud_keeps_the_mouse_while_imgui_wants_it():
    """A run's loop sets the input's mouse_captured_by_ui from ImGui's want_capture_mouse: over
    the HUD a held left button fires nothing; off it, it fires. (Headless: a source whose input
    is the world's, as the window's is, with the pointer fed to ImGui by hand.)"""
    from imgui_bundle import imgui

    from ecs_engine.app.app_session import AppSession, AppUI
    from ecs_engine.app.game_module import game_app
    from ecs_engine.app.loop import run
    from ecs_engine.app.offscreen import OffscreenSource
    from ecs_engine.app.settings import RunOptions
    from ecs_engine.demos.asteroids_game import Game

    seen: list[tuple[bool, bool, int]] = []
    holder: dict = {}

    class Probe(OffscreenSource):
        def attach(self, session):
            super().attach(session)
            self.input = session.world.resources[InputState] = InputState(pressed={"mouse_left"})

        def begin(self, session, frames_done):
            io = imgui.get_io()
            if frames_done == 3:
                io.add_mouse_pos_event(20.0, 20.0)  # over the HUD window (at 12, 12)
            if frames_done == 10:
                io.add_mouse_pos_event(300.0, 200.0)  # over the game
            if frames_done:
                game = session.world.resources[Game]
                seen.append((self.input.mouse_captured_by_ui, session.world.resources[ShipControls].fire, game.shots))
            return super().begin(session, frames_done)

    def make(options, source):
        holder["session"] = AppSession(game_app("asteroids"), options, source)
        return holder["session"]

    options = RunOptions(scene="cube", width=320, height=240, frames=16, validate=True, quiet=True, headless=True)
    result = run(options, Probe(), make_session=make, ui=lambda session, window: AppUI(session, window))
    assert result.validation_messages == []
    captured = [c for c, _, _ in seen]
    assert captured[:3] == [False, False, False] and captured[4:9] == [True] * 5 and captured[-3:] == [False] * 3
    assert all(fire == (not c) for c, fire, _ in seen)  # each frame's controls saw that frame's flag
    shots = [n for _, _, n in seen]
    assert shots[4] > 0 and shots[4] == shots[8] and shots[-1] > shots[8]  # no shots while over the HUD
