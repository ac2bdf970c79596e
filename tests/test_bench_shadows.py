"""`bench shadows --quick` on lavapipe: every light type and filter measured against the
shadowless frame, the JSON and the plot written, the target computed from the right rows."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_shadows_quick_writes_its_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main
    from bench.shadows import CONFIGS, QUICK_COUNTS, target_entry, thread_counts

    assert main(["shadows", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "shadows-ci.json").read_text())
    got = {(r["entities"], r["threads"], r["light"], r["filter"]) for r in doc["results"]}
    assert got == {(n, t, light, f) for n in QUICK_COUNTS for t in thread_counts() for light, f in CONFIGS}
    assert all(r["cpu_ms"] > 0 and r["gpu_ms"] and len(r["runs"]) == 2 for r in doc["results"])
    assert doc["target"]["ratio"] is None  # 100k entities are not in the quick run
    assert (tmp_path / "shadows-ci.png").stat().st_size > 1000
    made = target_entry(
        [
            {"entities": 100_000, "threads": 16, "light": "directional", "filter": "pcf", "cpu_ms": 9.0},
            {"entities": 100_000, "threads": 16, "light": "none", "filter": "-", "cpu_ms": 3.0},
        ],
        16,
    )
    assert made["ratio"] == 3.0 and made["met"] is False
