"""scripts/offline_suite.sh (wheelhouse + .debs for an offline GPU server) and `ecs-engine bench`.
The real fetch needs the network; here: its commands (DRY_RUN=1), its errors, and the CLI."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "offline_suite.sh"


def script(*args, env=None):
    return subprocess.run(
        ["bash", str(SCRIPT), *args], capture_output=True, text=True, timeout=120, env=dict(os.environ, **(env or {}))
    )


def test_help_and_bad_use():
    assert subprocess.run(["bash", "-n", str(SCRIPT)]).returncode == 0
    ok = script("--help")
    assert ok.returncode == 0 and "fetch DIR" in ok.stdout and "run DIR" in ok.stdout
    assert script().returncode == 2
    assert script("sideways", "x").returncode == 2


def test_fetch_lists_every_dependency_and_the_vulkan_debs(tmp_path):
    proc = script("fetch", str(tmp_path / "kit"), "3.12", env={"DRY_RUN": "1"})
    if proc.returncode == 2 and "apt-get not found" in proc.stderr:
        import pytest

        pytest.skip("not Debian or Ubuntu")
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    for dep in ("numpy", "numba", "vulkan", "imgui-bundle", "trimesh", "esper", "matplotlib"):
        assert dep in out
    assert "--python-version 3.12" in out and "--only-binary=:all:" in out
    assert "apt-get download libvulkan1 vulkan-validationlayers" in out


def test_run_refuses_a_folder_without_the_kit(tmp_path):
    proc = script("run", str(tmp_path))
    assert proc.returncode == 2 and "run fetch first" in proc.stderr


def test_cli_bench_runs_a_benchmark(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "ecs_engine", "bench", "numerics", "--quick", "--out", str(tmp_path), "--machine", "ci"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads((tmp_path / "numerics-ci.json").read_text())["benchmark"] == "numerics"
    bad = subprocess.run([sys.executable, "-m", "ecs_engine", "bench", "nope"], capture_output=True, text=True)
    assert bad.returncode == 2 and "unknown benchmark" in bad.stderr
