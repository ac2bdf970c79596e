"""The command line: demos run, bad input gives one line and exit 2, no traceback without --debug."""

from __future__ import annotations

import subprocess
import sys

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


def test_user_errors_are_one_line_and_debug_shows_traceback(monkeypatch, capsys):
    def boom(args):
        raise ValueError("Transform.position must be finite")

    monkeypatch.setattr(cli, "run", boom)
    assert cli.main(["demo"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == "ecs-engine: error: Transform.position must be finite"
    with pytest.raises(ValueError):
        cli.main(["--debug", "demo"])
    with pytest.raises(ValueError):
        cli.main(["demo", "--debug"])


def test_internal_errors_exit_1_with_a_hint(monkeypatch, capsys):
    def boom(args):
        raise RuntimeError("driver exploded")

    monkeypatch.setattr(cli, "run", boom)
    assert cli.main(["demo"]) == 1
    assert "run with --debug" in capsys.readouterr().err
