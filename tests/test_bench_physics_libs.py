"""The physics libraries' benchmark (bench/physics_libs.py) runs in quick mode with whatever
libraries this interpreter has, measures each one's pile, statics, rays and churn, and lists the
others as not installed."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_physics_libs_quick_writes_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["physics-libs", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "physics-libs-ci.json").read_text())
    assert doc["benchmark"] == "physics-libs" and doc["quick"] is True and doc["config"]["boxes"] == 300
    libraries = {lib["name"]: lib for lib in doc["libraries"]}
    assert set(libraries) == {"rapier3d", "culverin", "pybullet"}
    for name, lib in libraries.items():
        assert lib["installed"] == (importlib.util.find_spec(name) is not None), name
        if not lib["installed"]:
            continue
        pile = lib["pile"]
        assert pile["settled"] and pile["mean_height_after"] < pile["mean_height_before"], name  # the boxes fell
        assert pile["step_ms"] > 0 and pile["readback_ms"] > 0 and lib["statics"]["step_ms"] > 0
        assert lib["rays"]["hits"] == doc["config"]["rays"], name  # every ray lands on the pile or the floor
        assert lib["churn"]["add_ms"] > 0 and lib["churn"]["remove_ms"] > 0
        assert lib["deterministic"] is True, name  # the same world stepped alike, the same poses


def test_the_grid_places_every_body_apart():
    import numpy as np

    from bench.physics_libs import grid

    points = grid(1000, 1.2, 1.0)
    assert points.shape == (1000, 3) and points[:, 1].min() == 1.0
    gaps = np.linalg.norm(points[:, None] - points[None], axis=2) + np.eye(1000) * 9
    assert gaps.min() >= 1.2 - 1e-9  # unit boxes 1.2 apart: none starts inside another
