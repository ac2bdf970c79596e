"""The command line: demos run, bad input gives one line and exit 2, no traceback without --debug."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ecs_engine.app import cli


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "ecs_engine", *args], capture_output=True, text=True, timeout=120)


def test_motion_demo_runs_and_reports():
    proc = run_cli("demo", "motion", "--entities", "500", "--frames", "5")
    assert proc.returncode == 0, proc.stderr
    assert "500 entities spawned" in proc.stdout and "ns per entity" in proc.stdout


@pytest.mark.parametrize("args", [["demo", "--entities", "-4"], ["demo", "--frames", "x"], ["demo", "nope"], ["bogus"]])
def test_bad_arguments_exit_2_without_traceback(args):
    proc = run_cli(*args)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "error" in proc.stderr


def test_user_errors_are_one_line_and_debug_shows_traceback_with_the_same_exit_status(monkeypatch, capsys):
    def boom(args):
        raise ValueError("Transform.position must be finite")

    monkeypatch.setattr(cli, "run", boom)
    assert cli.main(["demo"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == "ecs-engine: error: Transform.position must be finite"
    for argv in (["--debug", "demo"], ["demo", "--debug"]):
        assert cli.main(argv) == 2  # a user's error stays exit 2 with --debug
        err = capsys.readouterr().err
        assert "Traceback" in err and "boom" in err
        assert err.strip().splitlines()[-1] == "ecs-engine: error: Transform.position must be finite"


def test_internal_errors_exit_1_with_a_hint(monkeypatch, capsys):
    def boom(args):
        raise RuntimeError("driver exploded")

    monkeypatch.setattr(cli, "run", boom)
    assert cli.main(["demo"]) == 1
    assert "run with --debug" in capsys.readouterr().err
    assert cli.main(["demo", "--debug"]) == 1
    assert "Traceback" in capsys.readouterr().err


ECS_ENGINE = str(Path(sys.executable).with_name("ecs-engine"))  # the installed console script


def needs_script(command):
    if command[0] == ECS_ENGINE and not Path(ECS_ENGINE).exists():
        pytest.skip("no ecs-engine script beside this Python")


@pytest.mark.parametrize(
    "command",
    [
        [sys.executable, "-m", "ecs_engine.bench", "--help"],
        [ECS_ENGINE, "bench", "--help"],
        [sys.executable, "-m", "ecs_engine", "demo", "motion", "--entities", "100", "--frames", "2"],
        [ECS_ENGINE, "demo", "motion", "--entities", "100", "--frames", "2"],
    ],
    ids=["python -m ecs_engine.bench", "ecs-engine bench", "python -m ecs_engine", "ecs-engine"],
)
def test_a_closed_pipe_ends_every_entry_point_quietly(command):
    """`... | head` that stops reading: no traceback, no "Broken pipe" error, the shell's 141."""
    needs_script(command)
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    proc.stdout.close()  # the reader is gone before the command writes its first line
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 141, err
    assert err == ""


def wait_for_library(proc, name, timeout=60.0):
    """Until the process has mapped a shared library whose path contains `name` (Linux)."""
    maps = Path(f"/proc/{proc.pid}/maps")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            if name in maps.read_text():
                return
        except OSError:
            pass
        time.sleep(0.005)
    raise AssertionError(f"{name} never loaded (exit {proc.poll()})")


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="watches /proc/PID/maps")
@pytest.mark.parametrize(
    "command, library",
    [
        ([sys.executable, "-m", "ecs_engine"], "llvmlite"),  # numba's import
        ([ECS_ENGINE], "llvmlite"),
        ([sys.executable, "-m", "ecs_engine"], "libvulkan"),  # the binding's import, the device
    ],
    ids=["python -m, numba import", "ecs-engine, numba import", "python -m, vulkan"],
)
def test_ctrl_c_during_start_up_is_one_line_and_exit_130(command, library):
    needs_script(command)
    args = ["demo", "cube", "--headless", "--frames", "100000", "--width", "32", "--height", "24"]
    proc = subprocess.Popen([*command, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for_library(proc, library)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert err.splitlines() == ["ecs-engine: interrupted"]


def test_audio_out_for_a_scene_without_sound_is_one_line_and_writes_nothing(tmp_path):
    wav = tmp_path / "x.wav"
    proc = run_cli(
        "demo", "cube", "--headless", "--frames", "2", "--width", "64", "--height", "48", "--audio-out", str(wav)
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        f"ecs-engine: error: --audio-out {wav}: cube makes no sound (no AudioPlugin), so there is nothing to capture"
    ]
    assert not wav.exists()
