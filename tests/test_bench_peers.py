"""`bench peers` (issue 17): the engine's side on lavapipe, pygfx's where the peers extra is
installed and wgpu finds an adapter, and the one-line refusal when pygfx is missing or cannot draw."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
TINY = ["--quick", "--frames", "3", "--warmup", "1", "--machine", "ci"]


def bench(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    return main


def pygfx_or_skip(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench import peers_pygfx

    missing = peers_pygfx.check_available()
    if missing is not None:
        pytest.skip(f"{missing} is not installed (the peers extra: pip install -e .[peers])")
    try:
        peers_pygfx.adapter_info()
    except RuntimeError as exc:
        pytest.skip(f"wgpu cannot draw here: {exc}")
    return peers_pygfx


def test_engine_side_writes_its_rows_and_ratios(tmp_path, monkeypatch, capsys):
    main = bench(monkeypatch)
    args = ["peers", *TINY, "--entities", "60", "--variants", "engine-instanced", "engine-indirect"]
    assert main([*args, "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "peers-ci.json").read_text())
    assert doc["benchmark"] == "peers" and doc["schema_version"] == 1 and doc["quick"] is True
    assert doc["machine"]["slug"] == "ci" and doc["machine"]["threads"] >= 1 and doc["machine"]["datetime_utc"]
    assert doc["device"] and doc["peer"] is None
    assert doc["config"]["size"] == [640, 360] and doc["config"]["entities"] == [60]
    rows = {r["variant"]: r for r in doc["results"]}
    assert set(rows) == {"engine-instanced", "engine-indirect"}  # lavapipe has drawIndirectCount
    for r in rows.values():
        assert r["entities"] == 60 and r["frames"] == 3 and r["visible"] > 0
        assert 0 < r["update_ms"] < r["wall_ms"] and r["render_ms"] > 0
    (ratio,) = doc["ratios"]
    assert ratio["engine_instanced_ms"] == rows["engine-instanced"]["wall_ms"]
    assert ratio["engine_indirect_x"] == pytest.approx(
        rows["engine-indirect"]["wall_ms"] / ratio["engine_instanced_ms"]
    )
    assert ratio["pygfx_instanced_x"] is None and ratio["pygfx_objects_x"] is None
    assert doc["plot"] == "peers-ci.png" and (tmp_path / "peers-ci.png").stat().st_size > 1000
    table = capsys.readouterr().out
    assert "engine-instanced" in table and "wall ms per frame" in table


def test_pygfx_side_writes_both_variants_and_skips_objects_past_the_cap(tmp_path, monkeypatch):
    pygfx_or_skip(monkeypatch)
    main = bench(monkeypatch)
    args = ["peers", *TINY, "--entities", "20", "60", "--objects-max", "30", "--out", str(tmp_path)]
    assert main(args) == 0
    doc = json.loads((tmp_path / "peers-ci.json").read_text())
    assert doc["peer"]["versions"]["pygfx"] and doc["peer"]["adapter"]["device"]
    assert doc["peer"]["renderer"]["pixel_scale"] == 1
    rows = {(r["entities"], r["variant"]): r for r in doc["results"]}
    assert len(rows) == 8
    for key in [(20, "pygfx-instanced"), (60, "pygfx-instanced"), (20, "pygfx-objects")]:
        r = rows[key]
        assert r["frames"] == 3 and not r["stopped_early"] and 0 < r["update_ms"] < r["wall_ms"]
    assert "wall_ms" not in rows[60, "pygfx-objects"] and "too slow" in rows[60, "pygfx-objects"]["skipped"]
    ratios = {r["entities"]: r for r in doc["ratios"]}
    assert ratios[20]["pygfx_objects_x"] > 0 and ratios[60]["pygfx_objects_x"] is None
    assert ratios[60]["pygfx_instanced_x"] == pytest.approx(
        rows[60, "pygfx-instanced"]["wall_ms"] / rows[60, "engine-instanced"]["wall_ms"]
    )


def test_pygfx_draws_the_engines_scene_and_keeps_to_its_budget(monkeypatch):
    peer = pygfx_or_skip(monkeypatch)
    from ecs_engine import World
    from ecs_engine.components import Transform, Velocity
    from ecs_engine.demos import scaling

    numbers = peer.scene_numbers(2_000)
    world = World()
    scaling.build(world, lambda mesh: 0, entities=2_000)
    assert np.array_equal(numbers.position, world.query(Transform, Velocity, write=()).column(Transform.position))
    assert 0 < numbers.knot.sum() < 20 and len(numbers.light_color) == 6
    canvas = peer.Canvas()
    try:
        for variant in ("instanced", "objects"):
            row = peer.measure(canvas, peer.scene_numbers(200), variant, frames=10, warmup=0, budget_s=0.0)
            assert row["frames"] == 3 and row["stopped_early"]  # past the budget: 3 frames, not 10
            assert canvas.last is not None and canvas.last.shape == (360, 640, 4)
            colours = len(np.unique(canvas.last[..., :3].reshape(-1, 3), axis=0))
            assert colours > 50, f"{variant}: the frame has {colours} colours (nothing drawn?)"
    finally:
        canvas.close()


def test_missing_pygfx_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    main = bench(monkeypatch)
    monkeypatch.setitem(sys.modules, "pygfx", None)  # `import pygfx` raises ImportError
    assert main(["peers", *TINY, "--out", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "pip install -e .[peers]" in lines[0], err
    assert not list(tmp_path.iterdir())


def test_no_adapter_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    main = bench(monkeypatch)
    from bench import peers_pygfx

    def no_adapter():
        raise RuntimeError("wgpu found no GPU adapter")

    monkeypatch.setattr(peers_pygfx, "check_available", lambda: None)
    monkeypatch.setattr(peers_pygfx, "adapter_info", no_adapter)
    assert main(["peers", *TINY, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == ["bench: pygfx cannot draw here: wgpu found no GPU adapter"]


def test_bad_sizes_are_refused_in_one_line(tmp_path, monkeypatch, capsys):
    main = bench(monkeypatch)
    for bad in (["--entities", "0"], ["--frames", "0"], ["--budget", "-1"]):
        assert main(["peers", *TINY, *bad, "--variants", "engine-instanced", "--out", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and err.startswith("bench: --"), err
