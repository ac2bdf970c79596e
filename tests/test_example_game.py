"""docs/examples/dodge.py, a game written from the docs alone, as a user runs it: `ecs-engine
play` headless and in a window (Xvfb), `ecs-engine editor`, driven by input scripts through its
state machine (menu, playing, paused, game over, restart), replayed from its own recording to the
same world, and its own option refusing a bad value."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_play_file import main as play  # the CLI in this process: (status, stdout, stderr)

GAME = str(Path(__file__).resolve().parent.parent / "docs" / "examples" / "dodge.py")
SMALL = ("--width", "160", "--height", "90", "--threads", "1")

# Frames are 1-based in a script. With --lives 1 and the default seed the player, left standing
# in the middle, is hit by a rock after about 90 frames of play: game over comes by frame 140.
START_PAUSE_RESUME = "5 down space\n6 up space\n30 down p\n31 up p\n45 down p\n46 up p\n"
RESTART = "150 down r\n151 up r\n"


def ending(out: str) -> dict[str, str]:
    """The game's summary line: `dodge: STATE path A>B score S lives L rocks R x X world HASH`."""
    line = r"^dodge: ([A-Z_]+) path (\S+) score (\d+) lives (\d+) rocks (\d+) x (-?[\d.]+) world (\w+)$"
    found = re.findall(line, out, re.M)
    assert len(found) == 1, out
    return dict(zip(("state", "path", "score", "lives", "rocks", "x", "world"), found[0], strict=True))


def colours(path: Path) -> dict[str, int]:
    """Pixels of the ground (green), the player (blue, or red when hurt) and the rocks (pale grey)."""
    rgb = np.asarray(Image.open(path))[..., :3].astype(np.int64)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return {
        "ground": int(((g > r + 40) & (g > b + 40)).sum()),
        "blue": int(((b > r + 80) & (b > 150)).sum()),
        "red": int(((r > g + 80) & (r > b + 80)).sum()),
        "rocks": int(((r > 170) & (np.abs(r - g) < 25) & (np.abs(g - b) < 30)).sum()),
    }


def test_headless_the_script_drives_menu_play_pause_game_over_and_restart(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "over.txt").write_text(START_PAUSE_RESUME)
    argv = ["play", GAME, "--headless", "--width", "320", "--height", "180", "--threads", "1", "--lives", "1"]
    code, out, err = play(capsys, *argv, "--frames", "140", "--input-script", "over.txt", "--screenshot", "over.png")
    assert code == 0, err
    over = ending(out)
    assert over["state"] == "GAME_OVER" and over["lives"] == "0"
    assert over["path"] == "MENU>PLAYING>PAUSED>PLAYING>GAME_OVER"
    seen = colours(tmp_path / "over.png")
    assert seen["ground"] > 3000 and seen["red"] > 50 and seen["blue"] < 20 and seen["rocks"] > 30, seen

    (tmp_path / "again.txt").write_text(START_PAUSE_RESUME + RESTART)
    code, out, err = play(capsys, *argv, "--frames", "170", "--input-script", "again.txt", "--screenshot", "again.png")
    assert code == 0, err
    again = ending(out)
    assert again["path"] == "MENU>PLAYING>PAUSED>PLAYING>GAME_OVER>PLAYING"
    assert again["state"] == "PLAYING" and again["lives"] == "1" and again["rocks"] == "12"
    seen = colours(tmp_path / "again.png")  # a new game: the player is well again
    assert seen["blue"] > 50 and seen["red"] < 20, seen


def test_a_recorded_run_replays_to_the_same_world(tmp_path, capsys, monkeypatch):
    """A run driven by a script and recorded; the recording replayed gives the same world hash,
    and a run driven differently gives another."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "keys.txt").write_text("3 down space\n4 up space\n10 down d\n40 up d\n50 down a\n")
    (tmp_path / "other.txt").write_text("3 down space\n4 up space\n10 down a\n40 up a\n")
    argv = ["play", GAME, "--headless", *SMALL, "--frames", "80"]
    code, out, err = play(capsys, *argv, "--input-script", "keys.txt", "--record-input", "rec.txt")
    assert code == 0, err
    first = ending(out)
    assert first["state"] == "PLAYING" and (tmp_path / "rec.txt").stat().st_size > 0
    code, out, err = play(capsys, *argv, "--input-script", "rec.txt")
    assert code == 0, err
    assert ending(out) == first
    code, out, err = play(capsys, *argv, "--input-script", "other.txt")
    assert code == 0, err
    other = ending(out)
    assert other["state"] == "PLAYING" and other["world"] != first["world"]


def test_a_gamepad_starts_steers_and_pauses(tmp_path, capsys, monkeypatch):
    """The actions' gamepad bindings: A starts, the left stick steers (right: +x), Start pauses
    and resumes; keys and stick reach the same place."""
    monkeypatch.chdir(tmp_path)
    pad = "3 down gamepad_a\n4 up gamepad_a\n10 axis gamepad_left_x 1.0\n30 axis gamepad_left_x 0\n"
    pad += "35 down gamepad_start\n36 up gamepad_start\n50 down gamepad_start\n51 up gamepad_start\n"
    (tmp_path / "pad.txt").write_text(pad)
    (tmp_path / "keys.txt").write_text("3 down enter\n4 up enter\n10 down right\n30 up right\n")
    argv = ["play", GAME, "--headless", *SMALL, "--frames", "60"]
    code, out, err = play(capsys, *argv, "--input-script", "pad.txt")
    assert code == 0, err
    by_pad = ending(out)
    assert by_pad["path"] == "MENU>PLAYING>PAUSED>PLAYING" and float(by_pad["x"]) > 3.0
    code, out, err = play(capsys, *argv, "--input-script", "keys.txt")
    assert code == 0, err
    assert ending(out)["x"] == by_pad["x"]


def test_restart_from_pause_begins_a_new_game(tmp_path, capsys, monkeypatch):
    """R (gamepad Y) while paused: a one-shot new game (every rock dropped anew, the player back in
    the middle), then playing; the same run without it keeps its rocks and place."""
    monkeypatch.chdir(tmp_path)
    keys = "3 down space\n4 up space\n6 down d\n20 up d\n25 down p\n26 up p\n"
    (tmp_path / "kept.txt").write_text(keys)
    (tmp_path / "again.txt").write_text(keys + "30 down gamepad_y\n31 up gamepad_y\n")
    argv = ["play", GAME, "--headless", *SMALL, "--frames", "40"]
    code, out, err = play(capsys, *argv, "--input-script", "kept.txt")
    assert code == 0, err
    kept = ending(out)
    assert kept["path"] == "MENU>PLAYING>PAUSED" and float(kept["x"]) > 1.0
    code, out, err = play(capsys, *argv, "--input-script", "again.txt")
    assert code == 0, err
    again = ending(out)
    assert again["path"] == "MENU>PLAYING>PAUSED>PLAYING" and again["x"] == "0.00" and again["rocks"] == "12"
    assert again["world"] != kept["world"]


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_windowed_under_xvfb_the_script_plays_as_it_does_headless(tmp_path, capsys, monkeypatch):
    """A script steps its run as it says, in a window too: the same game over, the same world."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "keys.txt").write_text(START_PAUSE_RESUME)
    size = ("--width", "320", "--height", "180", "--threads", "1")  # the game-over HUD covers a smaller one
    argv = ["play", GAME, *size, "--lives", "1", "--frames", "140", "--input-script", "keys.txt"]
    code, out, err = play(capsys, *argv, "--screenshot", "window.png", "--validate")
    assert code == 0, err
    assert out.startswith("dodge: window 320x180"), out
    windowed = ending(out)
    assert windowed["path"] == "MENU>PLAYING>PAUSED>PLAYING>GAME_OVER"
    seen = colours(tmp_path / "window.png")
    assert seen["ground"] > 500 and seen["red"] > 10, seen
    code, out, err = play(capsys, *argv, "--headless")
    assert code == 0, err
    assert ending(out) == windowed


def test_the_editor_shows_the_game_s_world(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["editor", GAME, "--headless", "--frames", "8", "--width", "640", "--height", "400", "--threads", "1"]
    code, out, err = play(capsys, *argv, "--screenshot", "editor.png")
    assert code == 0, err
    assert ending(out)["state"] == "MENU"
    rgb = np.asarray(Image.open(tmp_path / "editor.png"))[..., :3].astype(np.int64)
    scene = rgb[40:360, 260:440]  # the editor's central scene view at 640x400, between its panels
    r, g, b = scene[..., 0], scene[..., 1], scene[..., 2]
    assert ((g > r + 40) & (g > b + 40)).sum() > 1000  # the ground
    assert ((b > r + 80) & (b > 150)).sum() > 50  # the player


@pytest.mark.parametrize("value", ["0", "10", "many"])
def test_a_bad_lives_value_is_one_line_and_exit_2(capsys, value):
    code, out, err = play(capsys, "play", GAME, "--headless", "--frames", "1", "--lives", value)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "--lives" in err and "a whole number from 1 to 9" in err, err
