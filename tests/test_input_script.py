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
    ],
)
def test_a_bad_script_is_one_error_naming_the_line(tmp_path, text, message):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(UsageError, match=message):
        read_script(path)
    with pytest.raises(UsageError, match="cannot be read"):
        read_script(tmp_path / "missing.txt")


def test_a_recording_replays_the_same_presses_and_releases(tmp_path):
    """Including a key pressed and released between two frames, and one released and pressed."""
    recorder = InputRecorder(tmp_path / "rec.txt")
    live = InputState()
    events = {1: [("press", "w")], 2: [("press", "space"), ("release", "space")], 3: [("release", "w"), ("press", "w")]}
    seen = []
    for frame in range(5):
        for action, key in events.get(frame, []):
            getattr(live, action)(key)
        recorder.frame(frame, live)
        seen.append((set(live.pressed), set(live.just_pressed), set(live.just_released)))
        live.end_frame()
    recorder.write()
    script, replay = read_script(tmp_path / "rec.txt"), InputState()
    for frame, want in enumerate(seen):
        script.apply(frame, replay)
        assert (replay.pressed, replay.just_pressed, replay.just_released) == want, frame
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
    """The player's keys from a script: the same final line twice; recording that run and
    replaying the recording gives it again."""
    script = tmp_path / "fly.txt"
    script.write_text("5 down space\n5 down left\n40 up left\n60 down w\n120 up w\n150 up space\n")
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
