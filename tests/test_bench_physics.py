"""`bench physics` (bench/physics.py) in quick mode: the engine's physics against the library's
own step, and the ray batch (needs the physics extra: `make test-physics`)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_physics_bench_quick_writes_json(tmp_path, monkeypatch, capsys):
    pytest.importorskip("culverin", reason="the physics extra (CPython 3.12+): make test-physics")
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["physics", "--quick", "--out", str(tmp_path), "--machine", "ci", "--threads", "2"]) == 0
    doc = json.loads((tmp_path / "physics-ci.json").read_text())
    assert doc["benchmark"] == "physics" and doc["quick"] is True and doc["library"]["name"] == "culverin"
    assert doc["config"]["boxes"] == 300 and doc["config"]["threads"] == doc["machine"]["threads"] == 2
    for workload in ("pile", "statics"):
        r = doc[workload]
        assert r["settled"], workload  # nothing fell through the floor
        assert 0 < r["library_step_ms"] <= r["system_step_ms"], workload
        assert r["added_ms"] == pytest.approx(r["system_step_ms"] - r["library_step_ms"], abs=r["system_step_ms"])
        assert r["added_fraction"] == pytest.approx(r["added_ms"] / r["library_step_ms"])
        assert 0 <= r["events_copy_ms"] <= r["events_ms"] and r["added_without_events_ms"] <= r["added_ms"]
    for name in ("rays", "statics_rays"):
        rays = doc[name]
        assert rays["hits"] == doc["config"]["rays"], name  # every ray lands on a body
        assert rays["same_as_library"] > 0.98 and 0 < rays["grid_ms"] and 0 < rays["library_ms"], name
        assert len(rays["python_loop_ns"]) == 2 and rays["remade"] <= rays["steps"], name
    met = {"added_met", "added_without_events_met", "rays_met"}
    assert set(doc["targets"]) == {"added_fraction_max", "rays_ms_max", *met}
    assert "target" in capsys.readouterr().out


def test_without_the_library_the_bench_is_one_line(tmp_path, monkeypatch, capsys):
    import sys

    monkeypatch.syspath_prepend(str(ROOT))
    monkeypatch.setitem(sys.modules, "culverin", None)
    from bench.__main__ import main

    assert main(["physics", "--quick", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'ecs_engine[physics]'" in err[0]
    assert not list(tmp_path.iterdir())
