"""`bench lights --quick` on lavapipe: every light count and light culling measured, what each
actually drew with (auto clusters and defers from CLUSTER_MIN_LIGHTS), the JSON and the plot written."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_lights_quick_writes_its_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main
    from bench.lights import QUICK_COUNTS, target_entry

    assert main(["lights", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "lights-ci.json").read_text())
    rows = {(r["lights"], r["culling"]): r for r in doc["results"]}
    assert set(rows) == {(n, c) for n in QUICK_COUNTS for c in ("loop", "clustered", "deferred", "auto")}
    assert all(r["gpu_ms"] and r["gpu_ms"] > 0 and len(r["runs"]) == 2 for r in doc["results"])
    assert not any(r["clustered"] for (n, c), r in rows.items() if c == "loop")
    assert all(r["clustered"] for (n, c), r in rows.items() if c == "clustered")
    from ecs_engine.render.lighting.clusters import CLUSTER_MIN_LIGHTS

    wanted = [n >= CLUSTER_MIN_LIGHTS for n in QUICK_COUNTS]
    assert [rows[n, "auto"]["clustered"] for n in QUICK_COUNTS] == wanted
    # auto lights the opaque meshes in compute with the clusters; deferred always; the others never
    assert [rows[n, "auto"]["form"] == "deferred" for n in QUICK_COUNTS] == wanted
    assert all(r["form"] == "deferred" for (n, c), r in rows.items() if c == "deferred")
    assert not any(r["form"] == "deferred" for (n, c), r in rows.items() if c in ("loop", "clustered"))
    assert doc["target"]["ratio"] is None  # 4,096 lights are not in the quick run
    assert (tmp_path / "lights-ci.png").stat().st_size > 1000
    made = target_entry(
        [{"lights": 4096, "culling": "auto", "gpu_ms": 3.0}, {"lights": 6, "culling": "auto", "gpu_ms": 2.0}]
    )
    assert made["ratio"] == 1.5 and made["met"]


def test_counts_and_cullings_pick_the_configurations(tmp_path, monkeypatch, capsys):
    """`--counts 6 --cullings auto` measures that one configuration (the old/new runs' 4,096 and 6
    lights with auto, scripts/device_run.sh); a bad list is refused by the parser (exit 2)."""
    monkeypatch.syspath_prepend(str(ROOT))
    import pytest

    from bench.__main__ import main

    args = ["lights", "--quick", "--counts", "6", "--cullings", "auto", "--out", str(tmp_path), "--machine", "ci"]
    assert main(args) == 0
    doc = json.loads((tmp_path / "lights-ci.json").read_text())
    assert [(r["lights"], r["culling"]) for r in doc["results"]] == [(6, "auto")]
    assert doc["config"]["counts"] == [6]
    for bad in (["--counts", "6,x"], ["--counts", "0"], ["--cullings", "auto,fast"]):
        with pytest.raises(SystemExit) as exited:
            main(["lights", "--quick", *bad, "--out", str(tmp_path)])
        assert exited.value.code == 2
    assert "unknown light culling 'fast'" in capsys.readouterr().err
