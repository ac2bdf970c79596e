"""The frame benchmark runs (tiny sizes, lavapipe) and writes its JSON with the issue-17 target."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_frame_quick_writes_json_with_the_target(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["frame", "--quick", "--frame-reuse", "both", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "frame-ci.json").read_text())
    assert doc["config"]["scene"] == "cube" and doc["config"]["mode"] == "instanced"
    reused, recorded = doc["results"]
    for row in (reused, recorded):
        assert 0 < row["cpu_ms_median"] <= row["cpu_ms_p99"] and row["draws"] >= 1
        before, after = row["python_loop_ns"]  # the core's speed around the run
        assert 1 < before < 10_000 and 1 < after < 10_000
    # the cube stands still: past the first frame of each slot, every frame is submitted again
    assert reused["frame_reuse"] and reused["replayed"] == 1.0
    assert not recorded["frame_reuse"] and recorded["replayed"] == 0.0
    (target,) = doc["targets"]
    assert target["target"] == 0.15 and type(target["met"]) is bool


def test_frame_through_app_runs_the_scene_as_a_game(tmp_path, monkeypatch):
    """`--through app`: the cube scene built by an App's startup system, run by `app.run`: the
    same draws, and the frames replayed as the demo's are (nothing but the App differs)."""
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["frame", "--quick", "--through", "app", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "frame-ci.json").read_text())
    assert doc["config"]["through"] == "app"
    (row,) = doc["results"]
    assert 0 < row["cpu_ms_median"] and row["draws"] >= 1 and row["replayed"] == 1.0
