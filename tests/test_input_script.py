"""Input scripts (app/input_script.py): parsed, refused clearly when bad, replayed into a
headless game deterministically, and a recording replays to the same run."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from ecs_engine.app.input_script import KEYS, InputRecorder, read_script
from ecs_engine.errors import UsageError


def test_the_key_names_are_the_windows():
    import glfw

    from ecs_engine.app.window import key_names

    assert KEYS == set(key_names(glfw).values())


def test_a_script_parses_and_applies_by_frame(tmp_path):
    path = tmp_path / "keys.txt"
    path.write_text("# a comment\n2 down w\n2 down space  # two at once\n\n5 up w\n")
    script = read_script(path)
    held: set[str] = set()
    seen = []
    for frame in range(7):
        script.apply(frame, held)
        seen.append(sorted(held))
    assert seen[1] == [] and seen[2] == ["space", "w"] and seen[5] == ["space"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 down\n", "line 1: expected 'FRAME down|up KEY'"),
        ("x down w\n", "line 1: the frame 'x' is not a whole number"),
        ("5 down w\n3 up w\n", "line 2: frame 3 comes before frame 5"),
        ("1 press w\n", "unknown action 'press'"),
        ("1 down f13\n", "unknown key 'f13'"),
    ],
)
def test_a_bad_script_is_one_error_naming_the_line(tmp_path, text, message):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(UsageError, match=message):
        read_script(path)
    with pytest.raises(UsageError, match="cannot be read"):
        read_script(tmp_path / "missing.txt")


def test_a_recording_replays_the_same_key_states(tmp_path):
    recorder = InputRecorder(tmp_path / "rec.txt")
    states = [set(), {"w"}, {"w", "space"}, {"space"}, set(), {"r"}]
    for frame, held in enumerate(states):
        recorder.frame(frame, held)
    recorder.write()
    script = read_script(tmp_path / "rec.txt")
    held: set[str] = set()
    for frame, want in enumerate(states):
        script.apply(frame, held)
        assert held == want


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
    assert run.returncode == 2 and "line 1: unknown key 'nope'" in run.stderr and "Traceback" not in run.stderr
