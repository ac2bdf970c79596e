"""The soak benchmark in its short form: entities spawned and destroyed every frame and every
settings switch (paths, recorders, threads, culling, scene) applied in a few hundred frames.
GPU memory in use returns to the same bytes, no validation message arrives, the churn alone
does not grow resident memory. The long form (100,000 frames) runs on the GPU host."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def soak(tmp_path, *args):
    from bench.__main__ import main

    assert main(["soak", "--quick", "--out", str(tmp_path), "--machine", "ci", *args]) == 0
    return json.loads((tmp_path / "soak-ci.json").read_text())


def test_every_switch_leaves_gpu_memory_as_it_was_and_no_validation_message(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    doc = soak(tmp_path, "--frames", "1400", "--switch-every", "140")
    assert doc["switches"] == 9 and doc["validation_messages"] == 0 and doc["config"]["validate"]
    assert {s["settings"].split()[0] for s in doc["samples"]} == {"grid100", "cube"}  # both scenes ran
    assert doc["growth"]["gpu_used_mib"] == 0.0  # the same bytes after the warm-up as at the end
    assert (tmp_path / "soak-ci.png").stat().st_size > 1000


def test_churn_alone_does_not_grow_resident_memory(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    doc = soak(tmp_path, "--frames", "1200", "--switch-every", "100000", "--no-validate")
    assert doc["switches"] == 0 and doc["samples"][-1]["entities"] > 200  # 20 a frame come and go
    assert abs(doc["growth"]["rss_mib"]) < 2.0, doc["growth"]
    assert doc["growth"]["gpu_used_mib"] == 0.0


@pytest.mark.slow
def test_long_soak_is_flat(tmp_path, monkeypatch):
    """`pytest -m slow`: 20,000 frames here; the 100,000-frame run is `ecs-engine bench soak`."""
    monkeypatch.syspath_prepend(str(ROOT))
    doc = soak(tmp_path, "--frames", "20000", "--switch-every", "300")
    assert doc["validation_messages"] == 0 and doc["growth"]["gpu_used_mib"] == 0.0
    assert doc["slopes"]["rss_mib_per_1k_frames"] < 1.0
