"""The ECS benchmark (`ecs-engine bench ecs`) runs end to end and writes a well-formed document.

Runs in-process with the hidden --tiny sizes (a few seconds); timings are not checked, only the
shape of the output.
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # `bench` is a folder of the repository, not an installed package
    sys.path.insert(0, str(ROOT))

from bench import __main__ as bench_main  # noqa: E402 - after the sys.path line above
from bench import ecs, machine  # noqa: E402

SLUG = "test-box-2c"


def _run(out: Path, *extra: str) -> dict:
    rc = bench_main.main(["ecs", "--quick", "--tiny", "--out", str(out), "--machine", SLUG, *extra])
    assert rc == 0
    path = out / f"ecs-{SLUG}.json"
    assert path.is_file()
    assert (out / f"ecs-{SLUG}.png").stat().st_size > 1000  # the plot beside it
    return json.loads(path.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def doc(tmp_path_factory: pytest.TempPathFactory) -> dict:
    return _run(tmp_path_factory.mktemp("bench"))


def _is_num(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def test_document_matches_schema(doc: dict) -> None:
    assert ecs.validate(doc) == []
    assert doc["benchmark"] == "ecs"
    assert doc["schema_version"] == 1
    assert doc["quick"] is True
    assert doc["machine"]["slug"] == SLUG
    assert doc["machine"]["threads"] == ecs.THREADS
    for key in (
        "hostname",
        "cpu_model",
        "cpu_count",
        "cpu_affinity",
        "memory_bytes",
        "os",
        "kernel",
        "python",
        "numpy",
        "numba",
        "gpu",
        "datetime_utc",
    ):
        assert key in doc["machine"], key
    assert isinstance(doc["errors"], list)


def test_results_rows(doc: dict) -> None:
    rows = doc["results"]
    for row in rows:
        assert isinstance(row["workload"], str)
        assert isinstance(row["entities"], int) and row["entities"] > 0
        assert row["engine"] in ("esper", "native", "native-mt", "native-numpy", "adapter")
        assert _is_num(row["seconds"]) and row["seconds"] > 0
        assert _is_num(row["ns_per_entity"]) and row["ns_per_entity"] > 0
    native = {(r["workload"], r["entities"]) for r in rows if r["engine"] == "native"}
    n = doc["config"]["entities"][0]
    for workload in ("query1", "query2", "query3", "query1_sum_x", "dynamic_world", "transform_frame"):
        assert (workload, n) in native, workload
    assert any(r["workload"] == "spawn" for r in rows if r["engine"] == "native")
    assert any(r["engine"] == "native-numpy" and r["workload"] == "transform_frame" for r in rows), doc["errors"]
    overhead = next(r for r in rows if r["workload"] == "query_overhead")
    assert overhead["tables"] == 256 and _is_num(overhead["us_per_table"])


def test_targets_and_memory(doc: dict) -> None:
    names = [t["name"] for t in doc["targets"]]
    assert len(names) >= 3 + (1 if any(r["engine"] == "esper" for r in doc["results"]) else 0)
    assert any(n.startswith("transform frame speed-up over esper (1 thread") for n in names) or not any(
        r["engine"] == "esper" for r in doc["results"]
    )
    ops = {"<": lambda m, t: m < t, "<=": lambda m, t: m <= t, ">=": lambda m, t: m >= t}
    for t in doc["targets"]:
        assert isinstance(t["name"], str) and isinstance(t["unit"], str)
        assert _is_num(t["target"]) and _is_num(t["measured"])
        assert type(t["met"]) is bool
        assert t["met"] == ops[t["op"]](t["measured"], t["target"])
    mem = doc["memory"]
    assert mem["memory_bytes"] >= mem["raw_column_bytes"] > 0
    assert mem["batches10"]["ratio_shrunk"] <= mem["batches10"]["ratio"]


def test_esper_rows_and_ratios(doc: dict) -> None:
    pytest.importorskip("esper")
    rows = doc["results"]
    n = doc["config"]["entities"][0]
    esper_rows = {(r["workload"], r["entities"]) for r in rows if r["engine"] == "esper"}
    for workload in ("query1", "query2", "query3", "query1_sum_x", "dynamic_world", "transform_frame"):
        assert (workload, n) in esper_rows, workload
    assert doc["checks"]["query_sums_match"] is True
    assert doc["checks"]["transform_max_abs_diff"] < 1e-3
    pairs = {(r["workload"], r["denominator"]) for r in doc["ratios"]}
    assert ("transform_frame", "native") in pairs
    assert ("transform_frame", "native-numpy") in pairs
    for r in doc["ratios"]:
        assert r["numerator"] == "esper" and _is_num(r["ratio"]) and r["ratio"] > 0


def test_adapter_column_follows_importability(doc: dict) -> None:
    available = importlib.util.find_spec("ecs_engine.esper_compat") is not None
    if not available:
        assert doc["adapter"]["available"] is False
        assert not any(r["engine"] == "adapter" for r in doc["results"])
        return
    assert doc["adapter"]["available"] is True
    adapter_rows = [r for r in doc["results"] if r["engine"] == "adapter"]
    adapter_errors = [e for e in doc["errors"] if e.startswith("adapter")]
    assert adapter_rows or adapter_errors


def test_runs_without_esper_or_adapter(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ecs, "esper", None)
    monkeypatch.setattr(ecs, "adapter_class", lambda: (None, "disabled by the test"))
    doc = _run(tmp_path)
    assert ecs.validate(doc) == []
    engines = {r["engine"] for r in doc["results"]}
    assert {"native", "native-numpy"} <= engines <= {"native", "native-mt", "native-numpy"}
    assert doc["ratios"] == []
    assert doc["versions"]["esper"] is None and doc["adapter"] == {"available": False, "reason": "disabled by the test"}


def test_unknown_benchmark_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert bench_main.main(["no-such-bench"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no-such-bench" in err[0] and "ecs" in err[0]


def test_bad_machine_slug(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert bench_main.main(["ecs", "--quick", "--out", str(tmp_path), "--machine", "../x"]) == 2
    assert "slug" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_machine_slugs() -> None:
    assert machine.gpu_slug("NVIDIA H100 80GB HBM3") == "h100"
    assert (
        machine.make_slug(
            "AMD EPYC 9654 96-Core Processor", [{"name": "NVIDIA H100 80GB HBM3", "driver": "550.54"}], 16
        )
        == "h100-16c"
    )
    assert machine.make_slug("Intel(R) Xeon(R) Platinum 8480+", None, 16) == "xeon-platinum-8480-16c"
    info = machine.describe(threads=1)
    assert machine.SLUG_RE.match(info["slug"])
    assert info["cpu_affinity"] >= 1 and info["threads"] == 1
