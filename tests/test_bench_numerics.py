"""The numerics benchmark runs (quick mode) and writes JSON of the documented shape and a plot;
its findings agree with the integrators' known stability."""

from __future__ import annotations

import json
import math
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_numerics_quick_writes_json_and_plot(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["numerics", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "numerics-ci.json").read_text())
    assert (tmp_path / "numerics-ci.png").stat().st_size > 1000
    assert doc["benchmark"] == "numerics" and doc["quick"] is True and "datetime_utc" in doc["machine"]
    rows = {(r["case"], r["integrator"], round(1 / r["dt"])): r for r in doc["integrators"]}
    assert all(r["ms_per_step"] > 0 for r in rows.values())
    # the exact step is exact and stable; implicit is stable; explicit breaks on the stiff spring
    assert all(r["error"] < 1e-9 and not r["unstable"] for k, r in rows.items() if k[1] == "exact")
    assert not any(r["unstable"] for k, r in rows.items() if k[1] == "implicit")
    assert rows[("stiff", "explicit", 15)]["unstable"] and rows[("stiff", "explicit", 15)]["error"] is None
    assert rows[("soft", "rk4", 960)]["error"] < rows[("soft", "explicit", 960)]["error"] * 1e-3
    far = doc["render_precision"][-1]
    assert far["distance"] >= 1e7 and far["camera_relative_px"] < 0.01 and far["world_space_px"] > 10
    assert math.isfinite(far["world_space_px"]) and any("camera-relative" in f for f in doc["findings"])
    # every render path draws the direct path's image (lavapipe here)
    render = doc["render_error"]
    assert len(render["rows"]) == 7 and render["rows"][0]["rmse"] == 0.0
    assert all(r["rmse"] < 1.0 and r["cpu_ms"] > 0 and r["visible"] > 0 for r in render["rows"])


def test_progress_bar_counts_steps(monkeypatch):
    import io

    monkeypatch.syspath_prepend(str(ROOT))
    from bench import Progress

    out = io.StringIO()
    progress = Progress("x", stream=out)
    progress.total = 2
    for what in ("a", "b"):
        with progress.step(what):
            pass
    lines = out.getvalue().splitlines()
    assert "[####################] 2/2] b:" in lines[-1] and "[##########..........] 1/2] a:" in lines[1]
