"""The parallel-schedule, scene-file and hierarchy benchmarks run (quick mode), check their own results, and
write JSON of the documented shape."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_schedule_quick_writes_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["schedule", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "schedule-ci.json").read_text())
    assert doc["benchmark"] == "schedule" and doc["quick"] is True and doc["systems"] == 8
    schedules = [(r["schedule"], r["threads"]) for r in doc["rows"]]
    assert schedules[0] == ("sequential", 1) and ("parallel", 1) in schedules
    assert all(r["frame_ms"] > 0 for r in doc["rows"]) and doc["speedup_best_vs_1_thread"] > 0


def test_scene_io_quick_writes_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["scene-io", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "scene-io-ci.json").read_text())
    assert doc["benchmark"] == "scene-io" and [r["entities"] for r in doc["rows"]] == [1_000, 5_000]
    assert all(r["save_s"] > 0 and r["load_s"] > 0 and r["file_mb"] > 0 for r in doc["rows"])


def test_hierarchy_quick_writes_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["hierarchy", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "hierarchy-ci.json").read_text())
    assert doc["benchmark"] == "hierarchy" and sorted({r["with_parent"] for r in doc["rows"]}) == [1_000, 10_000]
    assert all(r["still_ms"] > 0 and r["replanned_ms"] > 0 for r in doc["rows"])
