"""The culling-methods benchmark runs (quick mode, lavapipe): every method a mode offers, a JSON of
the documented shape, occlusion culling drawing no more than frustum culling; a bad method is one
usage error."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_culling_methods_quick_writes_json_with_every_method(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main
    from bench.culling_methods import METHODS

    assert main(["culling-methods", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "culling-methods-ci.json").read_text())
    assert doc["benchmark"] == "culling-methods" and doc["quick"] and doc["targets"] == []
    rows = {(r["mode"], r["culling"]): r for r in doc["results"]}
    assert set(rows) == set(METHODS)
    for r in rows.values():
        assert r["cpu_ms"] > 0 and r["wall_ms"] > 0 and r["fps"] > 0 and r["visible"] > 0
    n = doc["config"]["entities"][0]
    assert rows["indirect", "none"]["visible"] == rows["instanced", "none"]["visible"] == n
    assert rows["indirect", "occlusion"]["visible"] <= rows["indirect", "frustum"]["visible"] < n


def test_an_unknown_method_is_one_usage_error(tmp_path, monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    with pytest.raises(SystemExit) as exited:
        main(["culling-methods", "--quick", "--methods", "instanced:occlusion", "--out", str(tmp_path)])
    assert exited.value.code == 2
    assert "invalid choice: 'instanced:occlusion'" in capsys.readouterr().err
