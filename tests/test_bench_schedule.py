"""The parallel-schedule benchmark runs (quick mode), checks the parallel schedule against the
sequential one itself, and writes JSON of the documented shape."""

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
