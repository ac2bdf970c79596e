"""How benchmarks are started (issue 19): `ecs-engine bench --help` and `python -m ecs_engine.bench`
work from any folder, a run without --out writes to the user's cache (never into the checkout) and
says where, and `make bench` without BENCH prints the list instead of failing."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NAMES = ("ecs", "numerics", "scaling", "seed-tables")


def run(*args: str, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ if env is None else env, COLUMNS="200")  # help lines unwrapped, whatever the terminal
    return subprocess.run(
        [sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=300, check=False
    )


def results_listing() -> set[str]:
    return {str(p.relative_to(ROOT)) for p in (ROOT / "bench" / "results").rglob("*")}


@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_ecs_engine_bench_help_lists_the_benchmarks(tmp_path: Path, flag: str) -> None:
    proc = run("-m", "ecs_engine", "bench", flag, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "ecs-engine bench NAME" in proc.stdout and "python -m ecs_engine.bench" in proc.stdout
    assert all(name in proc.stdout for name in NAMES), proc.stdout


def test_ecs_engine_bench_without_a_name_lists_them_and_exits_2(tmp_path: Path) -> None:
    proc = run("-m", "ecs_engine", "bench", cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert all(name in proc.stderr for name in NAMES), proc.stderr


def test_ecs_engine_bench_name_help_shows_its_options(tmp_path: Path) -> None:
    proc = run("-m", "ecs_engine", "bench", "numerics", "--help", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "usage: ecs-engine bench numerics" in proc.stdout
    assert "--quick" in proc.stdout and "--out" in proc.stdout and "bench-results" in proc.stdout


def test_top_level_help_names_every_benchmark(tmp_path: Path) -> None:
    proc = run("-m", "ecs_engine", "--help", cwd=tmp_path)
    assert proc.returncode == 0 and all(name in proc.stdout for name in NAMES), proc.stdout


def test_python_m_ecs_engine_bench_works_outside_the_checkout(tmp_path: Path) -> None:
    proc = run("-m", "ecs_engine.bench", "--help", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "python -m ecs_engine.bench" in proc.stdout and "ecs-engine bench" in proc.stdout
    assert "python -m bench " not in proc.stdout  # that one only works inside the checkout
    proc = run("-m", "ecs_engine.bench", "ecs", "--help", cwd=tmp_path)
    assert proc.returncode == 0 and "usage: python -m ecs_engine.bench ecs" in proc.stdout, proc.stderr


def test_default_out_follows_xdg_cache_home(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import default_out

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert default_out() == tmp_path / "ecs_engine" / "bench-results"
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    for unset in ("", "relative/cache"):  # the XDG spec says to ignore a relative path
        monkeypatch.setenv("XDG_CACHE_HOME", unset)
        assert default_out() == tmp_path / "home" / ".cache" / "ecs_engine" / "bench-results"


def test_quick_run_without_out_writes_to_the_cache_and_says_where(tmp_path: Path) -> None:
    cache, work = tmp_path / "cache", tmp_path / "work"
    work.mkdir()
    before = results_listing()
    env = dict(os.environ, XDG_CACHE_HOME=str(cache))
    proc = run("-m", "ecs_engine", "bench", "ecs", "--quick", "--tiny", "--machine", "ci", cwd=work, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = cache / "ecs_engine" / "bench-results"
    assert (out / "ecs-ci.json").is_file() and (out / "ecs-ci.png").is_file()
    assert str(out / "ecs-ci.json") in proc.stderr
    assert not list(work.iterdir())  # nothing in the current folder either
    assert results_listing() == before


def make_bench(*args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("BENCH", "MAKEFLAGS", "MFLAGS", "MAKELEVEL")}
    return subprocess.run(
        ["make", "--no-print-directory", "-C", str(ROOT), "bench", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


@pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")
def test_make_bench_without_bench_prints_the_list_and_installs_nothing() -> None:
    # dry runs first: only the BENCH=... recipe may run scripts/bootstrap.sh (which can install)
    dry = make_bench("-n")
    assert dry.returncode == 0 and "bootstrap" not in dry.stdout, dry.stdout
    assert "bootstrap.sh --extras dev,bench" in make_bench("-n", "BENCH=ecs --quick").stdout
    proc = make_bench(f"PY={sys.executable}")
    assert proc.returncode == 0, proc.stderr
    assert all(name in proc.stdout for name in NAMES), proc.stdout
