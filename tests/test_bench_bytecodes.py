"""`bench bytecodes --quick`: the 1-cube frame's bytecodes counted, the schedule's and the
render's adding up to the whole and the modules' to it too, the engine's modules named."""

from __future__ import annotations

import json

from bench.__main__ import main


def test_the_quick_bytecodes_benchmark_writes_its_json(tmp_path, capsys):
    assert main(["bytecodes", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "bytecodes-ci.json").read_text())
    assert doc["benchmark"] == "bytecodes" and doc["quick"] is True and doc["config"]["scene"] == "cube"
    r = doc["results"]
    assert r["per_frame"] == r["schedule_per_frame"] + r["render_per_frame"]
    assert r["schedule_per_frame"] > 500 and r["render_per_frame"] > 1_000
    assert abs(sum(r["by_module"].values()) - r["per_frame"]) < 1e-6
    assert "ecs/schedule.py" in r["by_module"] and "render/frame/draw_frame.py" in r["by_module"]
    assert list(r["by_module"].values()) == sorted(r["by_module"].values(), reverse=True)
    assert "bytecodes a frame" in capsys.readouterr().out
