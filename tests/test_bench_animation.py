"""`bench animation --quick`: a small crowd of skinned characters, still meshes beside them, every
number the JSON promises present and consistent (per joint and per vertex derived from the
medians), and the table printed."""

from __future__ import annotations

import json

from bench.__main__ import main


def test_the_quick_animation_benchmark_writes_its_json(tmp_path, capsys):
    assert main(["animation", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "animation-ci.json").read_text())
    assert doc["benchmark"] == "animation" and doc["quick"] is True
    assert doc["config"]["joints"] == 24 and doc["config"]["vertices"] == 1728
    kinds = {(r["characters"], r["shadows"], r["still"]) for r in doc["results"]}
    assert kinds == {(20, False, False), (20, True, False), (20, False, True)}
    for r in doc["results"]:
        assert r["cpu_ms"] > 0 and len(r["runs"]) == 2
        moved = sum(r["systems_ms"].values())
        assert (moved == 0) == r["still"]  # the still meshes run no animation, hierarchy or skins
        assert abs(r["us_per_joint"] - 1e3 * moved / (20 * 24)) < 1e-9
    assert doc["target"]["met"] is None  # no 10k crowd in a quick run
    assert "characters" in capsys.readouterr().out
