"""The levels-of-detail build benchmark runs in quick mode and writes JSON of the documented shape
(docs/performance.md, "Building levels of detail")."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_lod_build_quick_writes_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["lod-build", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "lod-build-ci.json").read_text())
    assert doc["benchmark"] == "lod-build" and doc["quick"] is True
    assert [r["vertices"] for r in doc["rows"]] == [6_144, 33 * 33, 65 * 65]
    for row in doc["rows"]:
        assert row["cpu_seconds"] > 0 and row["peak_growth_bytes"] >= 0 and len(row["levels"]) == 3
        errors = [error for _, error in row["levels"]]
        assert errors == sorted(errors) and errors[0] >= 0
