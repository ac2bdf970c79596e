"""`bench bytecodes --quick`: the 1-cube frame's bytecodes counted, the parts adding up to the
whole, the modules named, and the same count twice (what the benchmark is for: a figure the
host's speed does not move)."""

from __future__ import annotations

import json

from bench.__main__ import main


def test_the_quick_bytecodes_benchmark_counts_the_same_twice(tmp_path, capsys):
    counts = []
    for run in range(2):
        out = tmp_path / str(run)
        assert main(["bytecodes", "--quick", "--out", str(out), "--machine", "ci"]) == 0
        doc = json.loads((out / "bytecodes-ci.json").read_text())
        assert doc["benchmark"] == "bytecodes" and doc["config"]["scene"] == "cube"
        r = doc["results"]
        assert r["per_frame"] == r["schedule_per_frame"] + r["render_per_frame"] > 1_000
        assert abs(sum(r["by_module"].values()) - r["per_frame"]) < 1e-6
        assert "ecs/schedule.py" in r["by_module"] and "render/frame/draw_frame.py" in r["by_module"]
        counts.append(r["per_frame"])
    assert counts[0] == counts[1]
    assert "bytecodes a frame" in capsys.readouterr().out
