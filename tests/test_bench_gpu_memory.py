"""`bench gpu-memory --quick` on lavapipe: every configuration measured in the form it asks for,
memory growing with what each adds (HDR colour, MSAA samples, the G-buffer), the OIT targets
aliased with the G-buffer."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_gpu_memory_quick_writes_its_json(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.__main__ import main
    from bench.gpu_memory import CONFIGS

    assert main(["gpu-memory", "--quick", "--out", str(tmp_path), "--machine", "ci"]) == 0
    doc = json.loads((tmp_path / "gpu-memory-ci.json").read_text())
    rows = {r["config"]: r for r in doc["results"]}
    assert set(rows) == set(CONFIGS)
    assert doc["config"]["width"] == 160 and doc["machine"] and doc["device"]
    forms = {name: r["form"] for name, r in rows.items()}
    assert forms["direct"] == "direct" and forms["hdr"] == forms["hdr-msaa4"] == forms["hdr-post"] == "hdr"
    assert forms["deferred"] == forms["deferred-oit"] == "deferred"
    size = {name: r["image_bytes"] for name, r in rows.items()}
    # each adds images the one before lacks: HDR colour; 4 samples of colour and depth; the
    # G-buffer's three; the two OIT targets, which the output graph places in the memory of the
    # G-buffer (dead after the lighting, before the accumulation): no more memory
    assert size["direct"] < size["hdr"] < size["hdr-msaa4"]
    assert size["hdr"] < size["deferred"] <= size["deferred-oit"]
    oit = rows["deferred-oit"]
    assert oit["graph_transient_bytes"] < oit["graph_unaliased_bytes"]  # aliased
    assert oit["graph_transient_bytes"] == rows["deferred"]["graph_transient_bytes"]
    assert rows["hdr-post"]["graph_transient_bytes"] > 0  # bloom and SSAO's chains
