"""The ECS benchmark's document: esper ratios, targets, the printed table, the schema check, the plot.

Everything here reads the rows the workloads produced and measures nothing itself: `ratios`
(esper seconds over each other engine's), `targets` (the engine's goals, met or not),
`format_table` (what `ecs-engine bench ecs` prints), `validate` (schema_version 1, described in
bench/ecs.py's docstring) and `plot` (ns per entity per workload, one bar per engine).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

SCHEMA_VERSION = 1


def ratios(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    by = {(x["workload"], x["entities"], x["engine"]): x["seconds"] for x in results}
    out = []
    for (workload, n, engine), sec in by.items():
        if engine == "esper":
            continue
        base = by.get((workload, n, "esper"))
        if base is not None and sec > 0:
            out.append(
                {"workload": workload, "entities": n, "numerator": "esper", "denominator": engine, "ratio": base / sec}
            )
    return out


def targets(results: list[dict[str, Any]], memory: dict[str, Any]) -> list[dict[str, Any]]:
    out = []

    def add(name: str, target: float, measured: float, unit: str, op: str, entities: int) -> None:
        met = {"<": measured < target, "<=": measured <= target, ">=": measured >= target}[op]
        out.append(
            {
                "name": name,
                "target": target,
                "measured": measured,
                "unit": unit,
                "op": op,
                "met": bool(met),
                "entities": int(entities),
            }
        )

    spawn = next(x for x in results if x["workload"] == "spawn" and x["engine"] == "native")
    add(
        "spawn_batch of 1M entities (Transform, Velocity, Mesh)",
        1.0,
        spawn["seconds"] * 1_000_000 / spawn["entities"],
        "s per 1M entities",
        "<",
        spawn["entities"],
    )
    ov = next(x for x in results if x["workload"] == "query_overhead")
    add("query overhead per matched table", 5.0, ov["us_per_table"], "us/table", "<", ov["entities"])
    add("memory_bytes / raw column bytes after spawn_batch", 1.5, memory["ratio"], "x", "<=", memory["entities"])
    frames = {(x["entities"], x["engine"]): x for x in results if x["workload"] == "transform_frame"}
    n = 100_000 if (100_000, "esper") in frames else max((k[0] for k in frames if k[1] == "esper"), default=0)
    esp = frames.get((n, "esper"))
    for engine, label in (("native", "1 thread"), ("native-mt", "all threads")):
        eng = frames.get((n, engine))
        if esp and eng:
            threads = eng.get("threads", 1)
            add(
                f"transform frame speed-up over esper ({label}: {threads})",
                100.0,
                esp["seconds"] / eng["seconds"],
                "x",
                ">=",
                n,
            )
    return out


_UNITS = {
    "query1": ("ns/entity", 1.0),
    "query2": ("ns/entity", 1.0),
    "query3": ("ns/entity", 1.0),
    "query1_sum_x": ("ns/entity", 1.0),
    "dynamic_world": ("ms/frame", 1e3),
    "transform_frame": ("ms/frame", 1e3),
    "spawn": ("s", 1.0),
    "spawn_10_batches": ("s", 1.0),
    "query_overhead": ("us/table", 1.0),
}


def _value(row: dict[str, Any]) -> float:
    unit, scale = _UNITS.get(row["workload"], ("s", 1.0))
    if unit == "ns/entity":
        return row["ns_per_entity"]
    if unit == "us/table":
        return row["us_per_table"]
    return row["seconds"] * scale


def _fmt(v: float | None) -> str:
    if v is None:
        return "-"
    if v >= 100:
        return f"{v:,.0f}"
    if v >= 10:
        return f"{v:.1f}"
    return f"{v:.3g}" if v >= 0.01 else f"{v:.2e}"


def format_table(doc: dict[str, Any]) -> str:
    cells: dict[tuple[str, int], dict[str, dict[str, Any]]] = {}
    for row in doc["results"]:
        cells.setdefault((row["workload"], row["entities"]), {})[row["engine"]] = row
    header = ["workload", "N", "unit", "esper", "engine", "adapter", "esper/engine"]
    lines = [header]
    for (workload, n), engines in cells.items():
        unit = _UNITS.get(workload, ("s", 1.0))[0]
        esp = engines.get("esper")
        variants = [("native", workload)]
        if "native-mt" in engines:
            variants.append(("native-mt", f"{workload} ({engines['native-mt'].get('threads')} threads)"))
        if "native-numpy" in engines:
            variants.append(("native-numpy", f"{workload} (engine numpy fallback)"))
        for engine, label in variants:
            eng = engines.get(engine)
            adp = engines.get("adapter") if engine == "native" else None
            ratio = esp["seconds"] / eng["seconds"] if esp and eng and eng["seconds"] > 0 else None
            lines.append(
                [
                    label,
                    f"{n:,}",
                    unit,
                    _fmt(_value(esp)) if esp else "-",
                    _fmt(_value(eng)) if eng else "-",
                    _fmt(_value(adp)) if adp else "-",
                    f"{ratio:.1f}x" if ratio is not None else "-",
                ]
            )
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    out = []
    for j, line in enumerate(lines):
        out.append(
            "  ".join(c.ljust(w) if i == 0 or i == 2 else c.rjust(w) for i, (c, w) in enumerate(zip(line, widths)))
        )
        if j == 0:
            out.append("  ".join("-" * w for w in widths))
    mem = doc["memory"]
    b10 = mem["batches10"]
    out.append("")
    out.append(
        f"memory after spawn_batch({mem['entities']:,}): {mem['memory_bytes'] / 1e6:.1f} MB held, "
        f"{mem['raw_column_bytes'] / 1e6:.1f} MB raw columns (x{mem['ratio']:.2f}); tracemalloc: "
        f"{mem['tracemalloc_retained_bytes'] / 1e6:.1f} MB retained, "
        f"{mem['tracemalloc_peak_bytes'] / 1e6:.1f} MB peak"
    )
    out.append(
        f"memory after 10 spawn_batch calls: x{b10['ratio']:.2f} of raw, x{b10['ratio_shrunk']:.2f} "
        "after shrink_to_fit()"
    )
    if mem["esper_tracemalloc_bytes_per_entity"] is not None:
        native_per = mem["tracemalloc_retained_bytes"] / mem["entities"]
        out.append(
            f"bytes per entity (tracemalloc): esper {mem['esper_tracemalloc_bytes_per_entity']:.0f}, "
            f"engine {native_per:.0f}"
        )
    out.append("")
    for t in doc["targets"]:
        out.append(
            f"target {'MET ' if t['met'] else 'MISS'}  {t['name']}: {t['measured']:.3g} {t['unit']} "
            f"(target {t['op']} {t['target']:g}, N={t['entities']:,})"
        )
    adapter = doc["adapter"]
    if not adapter["available"]:
        out.append(f"adapter column skipped: ecs_engine.esper_compat not importable ({adapter['reason']})")
    if doc["versions"]["esper"] is None:
        out.append("esper columns skipped: esper is not installed")
    for err in doc["errors"]:
        out.append(f"error: {err}")
    return "\n".join(out)


# ============================================================== schema
_ROW_KEYS = {"workload": str, "entities": int, "engine": str, "seconds": float, "ns_per_entity": float, "matched": int}
ENGINES = ("esper", "native", "native-mt", "native-numpy", "adapter")


def validate(doc: dict[str, Any]) -> list[str]:
    """Problems with `doc` against schema_version 1 (empty list: valid)."""
    bad: list[str] = []

    def need(obj: Any, key: str, typ: Any, where: str) -> Any:
        if not isinstance(obj, dict) or key not in obj:
            bad.append(f"{where}: missing {key!r}")
            return None
        val = obj[key]
        if typ is float:
            ok = isinstance(val, (int, float)) and not isinstance(val, bool) and math.isfinite(val)
        elif typ is int:
            ok = isinstance(val, int) and not isinstance(val, bool)
        else:
            ok = isinstance(val, typ)
        if not ok:
            bad.append(f"{where}.{key}: expected {getattr(typ, '__name__', typ)}, got {val!r}")
        return val

    if need(doc, "benchmark", str, "doc") != "ecs":
        bad.append("doc.benchmark must be 'ecs'")
    if doc.get("schema_version") != SCHEMA_VERSION:
        bad.append(f"doc.schema_version must be {SCHEMA_VERSION}")
    need(doc, "quick", bool, "doc")
    machine = need(doc, "machine", dict, "doc") or {}
    for key, typ in (
        ("hostname", str),
        ("cpu_model", str),
        ("cpu_affinity", int),
        ("python", str),
        ("numpy", str),
        ("datetime_utc", str),
        ("threads", int),
        ("slug", str),
    ):
        need(machine, key, typ, "machine")
    if "gpu" not in machine:
        bad.append("machine: missing 'gpu'")
    need(doc, "versions", dict, "doc")
    adapter = need(doc, "adapter", dict, "doc") or {}
    need(adapter, "available", bool, "adapter")
    need(doc, "config", dict, "doc")
    results = need(doc, "results", list, "doc") or []
    if not results:
        bad.append("doc.results is empty")
    for i, row in enumerate(results):
        for key, typ in _ROW_KEYS.items():
            need(row, key, typ, f"results[{i}]")
        if isinstance(row, dict) and row.get("engine") not in ENGINES:
            bad.append(f"results[{i}].engine: {row.get('engine')!r} not in {ENGINES}")
    for i, ratio in enumerate(need(doc, "ratios", list, "doc") or []):
        for key, typ in (
            ("workload", str),
            ("entities", int),
            ("numerator", str),
            ("denominator", str),
            ("ratio", float),
        ):
            need(ratio, key, typ, f"ratios[{i}]")
    memory = need(doc, "memory", dict, "doc") or {}
    for key in ("entities", "memory_bytes", "raw_column_bytes"):
        need(memory, key, int, "memory")
    need(memory, "ratio", float, "memory")
    b10 = need(memory, "batches10", dict, "memory") or {}
    for key in ("ratio", "ratio_shrunk"):
        need(b10, key, float, "memory.batches10")
    need(doc, "checks", dict, "doc")
    tlist = need(doc, "targets", list, "doc") or []
    if not tlist:
        bad.append("doc.targets is empty")
    for i, t in enumerate(tlist):
        for key, typ in (
            ("name", str),
            ("target", float),
            ("measured", float),
            ("unit", str),
            ("op", str),
            ("met", bool),
            ("entities", int),
        ):
            need(t, key, typ, f"targets[{i}]")
    need(doc, "errors", list, "doc")
    return bad


def plot(doc: dict[str, Any], path: Path) -> None:
    """Nanoseconds per entity for each workload at its largest size, one bar per engine (log)."""
    from . import pyplot, save_figure

    plt = pyplot()

    rows = doc["results"]
    workloads = [w for w in dict.fromkeys(r["workload"] for r in rows) if w != "query_overhead"]
    engines = list(dict.fromkeys(r["engine"] for r in rows))
    fig, ax = plt.subplots(figsize=(12, 4.6))
    width = 0.8 / max(len(engines), 1)
    labels = []
    for i, w in enumerate(workloads):
        n = max(r["entities"] for r in rows if r["workload"] == w)
        labels.append(f"{w}\n{n:,}")
        for j, e in enumerate(engines):
            hit = [r for r in rows if r["workload"] == w and r["engine"] == e and r["entities"] == n]
            if hit and hit[0]["ns_per_entity"] > 0:
                ax.bar(
                    i + j * width,
                    hit[0]["ns_per_entity"],
                    width,
                    color=f"C{j}",
                    label=e if i == 0 or e not in ax.get_legend_handles_labels()[1] else None,
                )
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(workloads)) + 0.4 - width / 2, labels, fontsize=7)
    ax.set_ylabel("ns per entity (lower is better)")
    ax.set_title("ECS workloads: ecs_engine (native, multi-threaded, NumPy fallback, esper adapter) against esper")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, path)
