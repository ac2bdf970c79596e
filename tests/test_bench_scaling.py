"""The scaling benchmark runs (tiny sizes, lavapipe) and writes its JSON and plot."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_scaling_quick_writes_json_and_plot(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["scaling", "--quick", "--entities", "60", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "scaling-ci.json").read_text())
    assert (tmp_path / "scaling-ci.png").stat().st_size > 1000
    configs = {(r["mode"], r["recorder"], r["threads"]) for r in doc["results"]}
    assert ("per_entity", "native", 1) in configs and ("instanced", "python", 1) in configs
    assert ("indirect", "gpu", 1) in configs
    for r in doc["results"]:
        assert r["entities"] == 60 and r["record_ms"] > 0 and r["cpu_ms"] > 0 and r["fps"] > 0
        assert r["visible"] > 0 and 0 < r["systems_ms"] < r["cpu_ms"]
        if r["mode"] == "per_entity":
            assert r["draws"] == r["visible"] + 1
        if r["mode"] == "indirect":  # (cube, knot) x windings at most, plus the billboards
            assert 2 <= r["draws"] <= 5 and r["ns_per_draw_record"] is None
    names = [t["name"] for t in doc["targets"]]
    assert any("ns per draw" in n for n in names) and all(type(t["met"]) is bool for t in doc["targets"])
    floor = doc["driver_floor"]
    assert floor["draws"] == 20_000 and floor["per_buffer"] > 0
    for key in ("push_draw_ns", "draw_ns", "push_ns"):
        assert 0 < floor[key] < 100_000
    assert floor["push_draw_ns"] > floor["draw_ns"]  # pushing costs something


def test_each_configuration_starts_from_the_same_scene(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    import numpy as np

    from bench.scaling import restore, snapshot
    from ecs_engine import World
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.components import Orbit, Transform

    world = World()
    scene_builder("scaling", 50)(world, lambda mesh: 0)
    start = snapshot(world)
    before = [
        world.query(Transform, write=()).column(Transform.position),
        world.query(Orbit, write=()).column(Orbit.phase),
    ]
    schedule = default_schedule()
    for _ in range(20):
        schedule.run(world, 1 / 60)
    moved = world.query(Transform, write=()).column(Transform.position)
    assert not np.array_equal(moved, before[0])
    restore(world, start)
    assert np.array_equal(world.query(Transform, write=()).column(Transform.position), before[0])
    assert np.array_equal(world.query(Orbit, write=()).column(Orbit.phase), before[1])
