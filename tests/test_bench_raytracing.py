"""The ray-tracing benchmark: on a device without ray tracing (lavapipe) it refuses in one line
and writes nothing; where the device traces rays (the GPU host) a quick run writes its JSON."""

from __future__ import annotations

import json
from pathlib import Path

from gpu_context import shared_device

ROOT = Path(__file__).resolve().parent.parent


def test_raytracing_quick(tmp_path, monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    code = main(["raytracing", "--quick", "--out", str(tmp_path), "--machine", "ci"])
    if shared_device().ray_tracing is None:
        assert code == 2
        errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("bench:")]
        assert len(errors) == 1 and "has no ray-tracing pipelines" in errors[0]  # one line, no traceback
        assert not (tmp_path / "raytracing-ci.json").exists()
        return
    assert code == 0
    doc = json.loads((tmp_path / "raytracing-ci.json").read_text())
    assert [b["mesh"] for b in doc["bottom"]] == ["cube", "sphere 32x16"]
    for b in doc["bottom"]:
        assert 0 < b["compacted_bytes"] <= b["bytes"] and b["build_gpu_ms"] > 0
    (top,) = doc["top"]
    assert top["instances"] == 1000 and top["build_gpu_ms"] > 0 and top["update_gpu_ms"] > 0
    assert {(f["shadows"], f["light_culling"]) for f in doc["frames"]} == {
        ("maps", "auto"),
        ("maps", "deferred"),
        ("raytraced", "auto"),
    }
    assert all(f["gpu_ms"] > 0 and f["cpu_ms"] > 0 for f in doc["frames"])


def test_raytracing_refuses_bad_options(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main

    assert main(["raytracing", "--repeat", "0"]) == 2
    assert "--repeat must be at least 1" in capsys.readouterr().err
