"""Input scripts (app/input_script.py): parsed, refused clearly when bad, replayed into a
headless game deterministically, and a recording replays to the same run."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from ecs_engine.app.input_script import InputRecorder, read_script
from ecs_engine.errors import UsageError
from ecs_engine.systems import InputState


def test_a_script_parses_and_applies_by_frame(tmp_path):
    path = tmp_path / "keys.txt"
    path.write_text("# a comment\n2 down w\n2 down left_shift  # two at once\n\n5 up w\n6 down mouse_left\n")
    script = read_script(path)
    state = InputState()
    seen = []
    for frame in range(7):
        script.apply(frame, state)
        seen.append((sorted(state.pressed), sorted(state.just_pressed), sorted(state.just_released)))
        state.end_frame()
    assert seen[1] == ([], [], []) and seen[2] == (["left_shift", "w"], ["left_shift", "w"], [])
    assert seen[3] == (["left_shift", "w"], [], [])  # held, no new edge
    assert seen[5] == (["left_shift"], [], ["w"]) and seen[6][1] == ["mouse_left"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 down\n", "line 1: expected 'FRAME down|up KEY'"),
        ("x down w\n", "line 1: the frame 'x' is not a whole number"),
        ("5 down w\n3 up w\n", "line 2: frame 3 comes before frame 5"),
        ("1 press w\n", "unknown action 'press'"),
        ("1 down f99\n", "unknown key or button 'f99'"),
        ("1 down lefft\n", "did you mean left"),
        ("1 axis gamepad_left_x\n", "line 1: expected 'FRAME axis AXIS VALUE'"),
        ("1 axis gamepad_lefty 0.5\n", "unknown gamepad axis 'gamepad_lefty'; did you mean gamepad_left_y"),
        ("1 axis gamepad_left_x 1.5\n", "an axis value is from -1 to 1, not 1.5"),
        ("1 axis gamepad_left_x nan\n", "VALUE 'nan' is not a finite number"),
        ("1 move 10\n", "expected 'FRAME move X Y'"),
        ("1 move 10 up\n", "Y 'up' is not a finite number"),
        ("1 scroll inf 0\n", "DX 'inf' is not a finite number"),
        ("1\n", "line 1: expected one of FRAME down|up KEY, FRAME axis AXIS VALUE"),
        ("1 down gamepad_aa\n", "did you mean gamepad_a"),
        ("1 text hello\n", "line 1: text is one JSON string in double quotes"),
        ('1 text "a" b\n', "line 1: text is one JSON string"),
        ("1 text\n", "line 1: text is one JSON string"),
        ('1 text "open\n', "line 1: text is one JSON string"),
        ("1 dt 0\n", "line 1: a frame's dt is from 1e-06 to 10 seconds, not 0"),
        ("1 dt -0.5\n", "a frame's dt is from 1e-06 to 10 seconds"),
        ("1 dt 1e9\n", "a frame's dt is from 1e-06 to 10 seconds, not 1e9"),
        ("1 dt nan\n", "SECONDS 'nan' is not a finite number"),
        ("1 dt\n", "expected 'FRAME dt SECONDS'"),
        ("1 dt 0.02\n1 dt 0.03\n", "line 2: frame 1 has a dt already"),
    ],
)
def test_a_bad_script_is_one_error_naming_the_line(tmp_path, text, message):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(UsageError, match=message):
        read_script(path)
    with pytest.raises(UsageError, match="cannot be read"):
        read_script(tmp_path / "missing.txt")


def test_text_is_one_json_string_and_a_recording_keeps_it(tmp_path):
    """Typed text (for the editor's fields): quotes, a # and escapes inside the string, a comment
    after it; the window's typed characters are recorded and replay the same."""
    path = tmp_path / "type.txt"
    path.write_text('2 text "level #2.scene"  # the path field\n3 text "a \\"quoted\\" \\u00e9"\n3 down enter\n')
    script, state = read_script(path), InputState()
    typed = []
    for frame in range(4):
        script.apply(frame, state)
        typed.append(state.text)
        state.end_frame()
    assert typed == ["", "", "level #2.scene", 'a "quoted" \u00e9']
    assert script.events[3] == [("text", 'a "quoted" \u00e9'), ("down", "enter")]
    recorder, live = InputRecorder(tmp_path / "rec.txt"), InputState()
    for frame, text in enumerate(typed):
        live.text = text
        if frame == 3:
            live.press("enter")
        recorder.frame(frame, live)
        live.end_frame()
    recorder.write()
    replay, again = read_script(tmp_path / "rec.txt"), InputState()
    for frame, text in enumerate(typed):
        replay.apply(frame, again)
        assert again.text == text
        again.end_frame()
    assert replay.events[3] == [("down", "enter"), ("text", 'a "quoted" \u00e9')]  # a key, then its character


def test_gamepads_and_the_mouse_by_frame(tmp_path):
    path = tmp_path / "pad.txt"
    path.write_text(
        "1 down gamepad_a\n1 axis gamepad_left_x -0.5\n2 move 100 50.5\n2 move 110 60\n"
        "3 scroll 0 -1\n3 up gamepad_a\n3 axis gamepad_left_x 0\n"
    )
    script, state = read_script(path), InputState()
    seen = []
    for frame in range(4):
        script.apply(frame, state)
        seen.append((sorted(state.just_pressed), sorted(state.just_released), dict(state.axes), state.mouse))
        seen[-1] += (state.mouse_delta, state.scroll)
        state.end_frame()
    assert seen[1][:3] == (["gamepad_a"], [], {"gamepad_left_x": -0.5}) and state.axis("gamepad_left_x") == 0.0
    assert seen[2][3:] == ((110.0, 60.0), (110.0, 60.0), (0.0, 0.0))
    assert seen[3][1] == ["gamepad_a"] and seen[3][2] == {"gamepad_left_x": 0.0} and seen[3][5] == (0.0, -1.0)


def test_a_recording_replays_the_same_presses_and_releases(tmp_path):
    """Including a key pressed and released between two frames, and one released and pressed."""
    recorder = InputRecorder(tmp_path / "rec.txt")
    live = InputState()
    events = {
        1: [("press", "w"), ("set_axis", "gamepad_right_trigger", 0.1 + 0.2)],
        2: [("press", "space"), ("release", "space"), ("move_mouse", 3.25, 4.0), ("move_mouse", 7.0, 1 / 3)],
        3: [("release", "w"), ("press", "w"), ("press", "gamepad_dpad_up"), ("set_axis", "gamepad_right_trigger", 0.0)],
        4: [("move_mouse", 7.0, 1 / 3)],  # not a move
    }
    seen = []

    def snapshot(state):
        return (set(state.pressed), set(state.just_pressed), set(state.just_released), dict(state.axes), state.mouse)

    for frame in range(6):
        for action, *args in events.get(frame, []):
            getattr(live, action)(*args)
        if frame == 5:
            live.scroll = (0.0, 2.5)
        recorder.frame(frame, live)
        seen.append(snapshot(live) + (live.scroll,))
        live.end_frame()
    recorder.write()
    text = (tmp_path / "rec.txt").read_text()
    assert "1 axis gamepad_right_trigger 0.30000000000000004" in text and "4 move" not in text
    script, replay = read_script(tmp_path / "rec.txt"), InputState()
    for frame, want in enumerate(seen):
        script.apply(frame, replay)
        assert snapshot(replay) + (replay.scroll,) == want, frame
        replay.end_frame()


def play(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env.pop("DISPLAY", None)
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "ecs_engine",
            "play",
            "asteroids",
            "--headless",
            "--width",
            "96",
            "--height",
            "64",
            *args,
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )


def test_a_replayed_game_ends_the_same_and_a_bad_script_stops_before_the_run(tmp_path):
    """The player's keys, gamepad and mouse from a script: the same final line twice; recording
    that run and replaying the recording gives it again."""
    script = tmp_path / "fly.txt"
    script.write_text(
        "5 down space\n5 down left\n40 up left\n60 down w\n80 axis gamepad_left_x 0.8\n"
        "100 axis gamepad_left_x 0\n110 move 20 10\n115 down gamepad_a\n120 up w\n140 up gamepad_a\n150 up space\n"
    )
    record = tmp_path / "rec.txt"
    runs = [play("--frames", "200", "--input-script", str(script), "--record-input", str(record))]
    runs.append(play("--frames", "200", "--input-script", str(record)))
    runs.append(play("--frames", "200", "--input-script", str(script)))
    lines = []
    for run in runs:
        assert run.returncode == 0, run.stderr
        lines.append(next(line for line in run.stdout.splitlines() if line.startswith("asteroids: score")))
    assert lines[0] == lines[1] == lines[2]
    assert " 0 shots" not in lines[0] and "world " in lines[0]  # the script fired; the columns' hash matched
    bad = tmp_path / "bad.txt"
    bad.write_text("1 down nope\n")
    run = play("--frames", "5", "--input-script", str(bad))
    assert (
        run.returncode == 2 and "line 1: unknown key or button 'nope'" in run.stderr and "Traceback" not in run.stderr
    )


def test_the_input_state_checks_names_and_keeps_edges_for_one_frame():
    state = InputState()
    with pytest.raises(ValueError, match="did you mean space"):
        state.down("spcae")
    state.press("a")
    state.release("a")  # pressed and released between two frames
    state.move_mouse(10.0, 20.0)
    state.move_mouse(15.0, 18.0)
    state.scroll = (0.0, -1.0)
    assert not state.down("a") and state.pressed_now("a") and state.released_now("a")
    assert state.mouse == (15.0, 18.0) and state.mouse_delta == (15.0, 18.0)
    state.end_frame()
    assert not state.pressed_now("a") and not state.released_now("a")
    assert state.mouse == (15.0, 18.0) and state.mouse_delta == (0.0, 0.0) and state.scroll == (0.0, 0.0)


def test_a_frame_steps_by_its_dt_line_else_by_the_fixed_step(tmp_path):
    from ecs_engine.app.settings import FIXED_DT, MAX_DT, SIM_STEP

    path = tmp_path / "steps.txt"
    path.write_text("0 dt 0.0213\n2 down w\n2 dt 0.25\n")
    script = read_script(path)
    assert [script.step(k) for k in range(4)] == [
        (0.0213, MAX_DT),
        (FIXED_DT, MAX_DT),
        (0.25, MAX_DT),
        (FIXED_DT, MAX_DT),
    ]
    assert script.clock().step == SIM_STEP  # steps as a window does
    (tmp_path / "keys.txt").write_text("2 down w\n")
    keys = read_script(tmp_path / "keys.txt")  # no dt lines: steps as a headless run, in a window too
    assert keys.step(0) == (FIXED_DT, FIXED_DT) and keys.clock().step == FIXED_DT
    state = InputState()
    script.apply(2, state)  # the dt line is no input
    assert state.pressed == {"w"}
    recorder = InputRecorder(tmp_path / "rec.txt")
    recorder.frame(0, InputState(), FIXED_DT)  # a headless frame: nothing to say
    recorder.frame(1, InputState(), 0.1 / 3)  # a window's: its step, exactly
    assert recorder.lines[1:] == [f"1 dt {0.1 / 3!r}"] and read_script_lines(tmp_path, recorder).steps == {1: 0.1 / 3}


def read_script_lines(tmp_path, recorder):
    recorder.write()
    return read_script(recorder.path)


STEPPED_GAME = """
from ecs_engine import App, DefaultPlugins
from ecs_engine.components import Camera, Mesh, Transform, Velocity
from ecs_engine.render.assets.meshes import Meshes
from ecs_engine.render.assets.primitives import cube_mesh


class Clock:
    seconds = 0.0


def setup(world, dt):
    cube = world.resources[Meshes].add(cube_mesh())
    world.spawn(Transform(), Mesh(handle=cube, material=0), Velocity(linear=(1.0, 0.0, 0.0)))
    world.spawn(Transform(position=(0.0, 0.0, 4.0)), Camera())


def count(world, dt):  # a per-frame stage: it sees each frame's step
    world.resources[Clock].seconds += dt


def build(app):
    app.add_plugins(DefaultPlugins)
    app.insert_resource(Clock())
    app.add_startup_systems(setup)
    app.add_systems("update", count)
    app.set_summary(lambda world: f"x {float(world.query(Velocity).column(Transform.position)[0, 0])!r} "
                    f"seconds {world.resources[Clock].seconds!r}")
"""


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_a_window_s_recording_replays_exactly_in_a_window_and_headless(tmp_path):
    """A window's frames take what they take: its recording writes each frame's dt, and replaying
    it steps the same, so the fixed stage (motion) and the per-frame stages end where they did."""
    game = tmp_path / "stepped.py"
    game.write_text(STEPPED_GAME)
    base = [sys.executable, "-m", "ecs_engine", "play", str(game), "--width", "48", "--height", "32", "--frames", "12"]

    def summary(*flags: str) -> str:
        run = subprocess.run([*base, *flags], capture_output=True, text=True, timeout=300, cwd=tmp_path)
        assert run.returncode == 0, run.stderr
        (line,) = [row for row in run.stdout.splitlines() if row.startswith("x ")]
        return line

    live = summary("--record-input", "rec.txt")
    steps = read_script(tmp_path / "rec.txt").steps
    assert len(steps) == 12 and len(set(steps.values())) > 1  # the wall clock's steps, one a frame
    assert summary("--headless", "--input-script", "rec.txt") == live
    assert summary("--input-script", "rec.txt") == live  # in a window again
    assert summary("--headless") != live  # (the fixed step alone ends elsewhere)
