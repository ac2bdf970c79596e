"""Describe the machine a benchmark runs on, and name it with a short filesystem-safe slug.

`describe(threads)` returns a JSON-ready dict:

    hostname, cpu_model, cpu_count (os.cpu_count()), cpu_affinity (len(os.sched_getaffinity(0))),
    memory_bytes (MemTotal), os (platform.platform()), kernel (platform.release()),
    python, python_implementation, numpy, numba (None when absent), gpu ({"name", "driver",
    "count"} of the first GPU nvidia-smi lists, or None when nvidia-smi is absent or fails),
    datetime_utc (ISO 8601), threads (what the benchmark uses), slug.

The slug is "<gpu>-<cores>c" when an NVIDIA GPU is present (e.g. "h100-16c", "h200x2-32c"),
otherwise "<cpu>-<cores>c" (e.g. "xeon-platinum-8480-16c"), where cores is the number of CPUs
this process may run on. `--machine SLUG` overrides it (validated by `check_slug`).
"""

from __future__ import annotations

import datetime as _dt
import os
import platform
import re
import shutil
import socket
import subprocess
import time
from typing import Any

SLUG_RE = re.compile(r"^[a-z0-9][a-z0-9._-]{0,63}$")

_VENDOR_WORDS = {"nvidia", "geforce", "tesla", "quadro"}
_CPU_STOP = {"intel", "amd", "r", "tm", "cpu", "processor", "core", "with", "genuine", "authentic"}


def _read(path: str) -> str:
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            return fh.read()
    except OSError:
        return ""


def cpu_model() -> str:
    info = _read("/proc/cpuinfo")
    for key in ("model name", "Model", "Hardware", "Processor", "cpu model"):
        m = re.search(rf"^{key}\s*:\s*(.+)$", info, re.MULTILINE)
        if m and m.group(1).strip():
            return m.group(1).strip()
    return platform.processor() or platform.machine() or "unknown"


def memory_bytes() -> int | None:
    m = re.search(r"^MemTotal:\s*(\d+)\s*kB", _read("/proc/meminfo"), re.MULTILINE)
    return int(m.group(1)) * 1024 if m else None


def affinity_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def gpus() -> list[dict[str, str]] | None:
    """[{"name", "driver"}] per GPU from nvidia-smi; None when it is absent or fails."""
    exe = shutil.which("nvidia-smi")
    if exe is None:
        return None
    try:
        out = subprocess.run(
            [exe, "--query-gpu=name,driver_version", "--format=csv,noheader"],
            capture_output=True,
            text=True,
            timeout=20,
            check=True,
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    found = []
    for line in out.splitlines():
        if line.strip():
            name, _, driver = line.rpartition(",")
            found.append({"name": name.strip(), "driver": driver.strip()})
    return found or None


def _version(module: str) -> str | None:
    try:
        mod = __import__(module)
    except ImportError:
        return None
    return str(getattr(mod, "__version__", "unknown"))


def _clean(text: str) -> str:
    text = re.sub(r"[^a-z0-9.]+", "-", text.lower()).strip("-.")
    return re.sub(r"-{2,}", "-", text)


def gpu_slug(name: str) -> str:
    """ "NVIDIA H100 80GB HBM3" -> "h100"; "NVIDIA GeForce RTX 4090" -> "rtx4090"."""
    tokens = [t for t in re.split(r"[\s_-]+", name.lower()) if t and t not in _VENDOR_WORDS]
    keep: list[str] = []
    for tok in tokens:
        # Memory sizes and form factors do not name the chip.
        if re.fullmatch(r"\d+gb|pcie|sxm\d*|hbm\d*e?|nvl|mig.*", tok):
            break
        keep.append(tok)
        if re.search(r"\d", tok):
            break
    return _clean("".join(keep[:2])) or "gpu"


def cpu_slug(model: str) -> str:
    """ "Intel(R) Xeon(R) Platinum 8480+" -> "xeon-platinum-8480"; "AMD EPYC 7763 ..." -> "epyc-7763"."""
    text = re.sub(r"\((r|tm)\)", " ", model.lower()).split("@")[0]
    tokens = [
        t
        for t in re.split(r"[^a-z0-9]+", text)
        if t and t not in _CPU_STOP and not re.fullmatch(r"\d+(st|nd|rd|th)|gen", t)
    ]
    keep: list[str] = []
    for tok in tokens:
        keep.append(tok)
        if re.search(r"\d", tok) and len(tok) >= 3:
            break
    slug = _clean("-".join(keep[:4]))[:28].strip("-.")
    return slug or _clean(platform.machine()) or "cpu"


def make_slug(model: str, gpu_list: list[dict[str, str]] | None, cores: int) -> str:
    if gpu_list:
        base = gpu_slug(gpu_list[0]["name"])
        if len(gpu_list) > 1:
            base += f"x{len(gpu_list)}"
    else:
        base = cpu_slug(model)
    return f"{base}-{cores}c"


def check_slug(slug: str) -> str:
    if not SLUG_RE.match(slug):
        raise ValueError(
            f"machine slug {slug!r} is not filesystem-safe: use lower-case letters, digits, "
            "'.', '_' and '-' (64 characters at most, starting with a letter or digit)"
        )
    return slug


def python_loop_ns(iterations: int = 200_000, repeats: int = 5) -> float:
    """How fast this core runs Python now: ns per iteration of a fixed loop of dict reads and
    additions, the best of `repeats`. A virtual machine's core speed drifts; the H100 host
    measured 43 to 115 ns within minutes, and every part of a small frame moved with it, so the
    frame benchmark reports it beside each run."""
    table = {i: i for i in range(64)}
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter_ns()
        total = 0
        for i in range(iterations):
            total += table[i & 63]
        best = min(best, time.perf_counter_ns() - start)
    return best / iterations


def describe(threads: int = 1, slug: str | None = None) -> dict[str, Any]:
    model = cpu_model()
    gpu_list = gpus()
    cores = affinity_count()
    return {
        "hostname": socket.gethostname(),
        "cpu_model": model,
        "cpu_count": os.cpu_count(),
        "cpu_affinity": cores,
        "memory_bytes": memory_bytes(),
        "os": platform.platform(),
        "kernel": platform.release(),
        "python": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "numpy": _version("numpy"),
        "numba": _version("numba"),
        "gpu": dict(gpu_list[0], count=len(gpu_list)) if gpu_list else None,
        "datetime_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "threads": int(threads),
        "slug": check_slug(slug) if slug else make_slug(model, gpu_list, cores),
    }


if __name__ == "__main__":  # pragma: no cover - convenience
    import json

    print(json.dumps(describe(), indent=2))


class _Silent:
    """Progress for a standalone run: nothing printed."""

    total = 0

    def step(self, what: str) -> Any:
        from contextlib import nullcontext

        return nullcontext()


def standalone(doc: str | None, add_arguments: Any, run: Any, argv: list[str] | None = None) -> int:
    """A benchmark module run as a script (`python3 bench/NAME.py`, with whichever ecs_engine is
    importable): its options and --quick, its run, no JSON written."""
    import argparse

    parser = argparse.ArgumentParser(description=(doc or "").splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="tiny sizes: a smoke run in seconds")
    add_arguments(parser)
    run(parser.parse_args(argv), {}, _Silent())
    return 0
