"""The seed-tables benchmark runs (quick mode, lavapipe) and writes JSON of the documented shape."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_seed_tables_quick_writes_its_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    import bench.seed_tables as seed_tables
    from bench.__main__ import main

    monkeypatch.setattr(seed_tables, "SCENES", ("cube",))  # one scene, one mode, keeps CI fast
    monkeypatch.setattr(seed_tables, "MODES", ("per_entity",))
    monkeypatch.setattr(seed_tables, "THREADS", 2)
    assert main(["seed-tables", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "seed-tables-ci.json").read_text())
    assert (tmp_path / "seed-tables-ci.png").stat().st_size > 1000
    assert doc["benchmark"] == "seed-tables" and doc["quick"] is True
    for key in ("hostname", "cpu_model", "python", "datetime_utc", "threads"):
        assert key in doc["machine"]
    assert [(r["mode"], r["threads"]) for r in doc["results"]] == [("per_entity", 1), ("per_entity", 2)]
    row = doc["results"][0]
    assert row["scene"] == "cube" and row["frames"] > 0 and row["validation_messages"] == 0
    assert row["record_ms_mean"] > 0
    assert row["fps"] > 0 and row["cpu_ms_mean"] > 0 and row["gpu_ms_mean"] > 0
    assert 0 <= row["cpu_system_percent"] <= 100 and row["cpu_process_percent"] >= 0
    assert doc["seed"]["grid100"]["cpu_ms"] == [3.5, 2.4]
    windowed = doc["windowed"]
    if os.environ.get("DISPLAY"):  # under xvfb-run (make test): a window on lavapipe
        assert [r["scene"] for r in windowed["rows"]] == ["cube"]
        row = windowed["rows"][0]
        assert row["window"] is True and row["present"] in ("immediate", "mailbox", "fifo") and row["fps"] > 0
    else:
        assert windowed == {"skipped": "no display"}
    overlay = doc["overlay"]
    assert overlay["cpu_ms_on"] > 0 and overlay["cpu_ms_off"] > 0 and overlay["ui_ms_mean"] > 0
    assert overlay["difference_ms"] == overlay["cpu_ms_on"] - overlay["cpu_ms_off"]
    assert type(overlay["met"]) is bool and overlay["target_ms"] == 0.3


def test_headless_runs_never_load_glfw(tmp_path):
    import subprocess

    code = (
        "import sys; from ecs_engine.app.loop import run; from ecs_engine.app.settings import RunOptions; "
        "run(RunOptions(scene='cube', width=32, height=24, frames=1, quiet=True)); "
        "print('glfw' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
