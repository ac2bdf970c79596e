"""The culling benchmark runs (quick mode): temporal culling against exact per-frame culling over
camera paths, no false negatives, a JSON of the documented shape and its plot."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_culling_quick_writes_json_and_plot(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["culling", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "culling-ci.json").read_text())
    assert doc["benchmark"] == "culling" and (tmp_path / doc["plot"]).stat().st_size > 10_000
    assert {r["path"] for r in doc["rows"]} == {"walk", "fast-turn"}
    assert all(r["false_negatives"] == 0 and r["frustum_ms"] > 0 and r["temporal_ms"] > 0 for r in doc["rows"])
    held = [r for r in doc["rows"] if r["min_interval_s"] > 0]
    assert held and all(r["extra_draws_per_frame"] > 0 for r in held)  # held rows are drawn: extra
    assert all(r["extra_draws_per_frame"] < 0.01 * r["entities"] for r in doc["rows"] if r["min_interval_s"] == 0)
