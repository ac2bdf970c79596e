"""`python -m bench NAME [--quick] [--out DIR] [--machine SLUG]`

Runs one registered benchmark, prints its table on stdout (progress goes to stderr) and writes
`<out>/<NAME>-<slug>.json` (default out: bench/results). Exit codes: 0 done, 2 usage error.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
from pathlib import Path
from typing import Any

from . import Progress
from .machine import check_slug, describe

# Benchmark name -> module of this package (imported only when run). Add new benchmarks here.
# The package is `bench` in the repository and `ecs_engine.bench` once installed.
REGISTRY: dict[str, str] = {
    "ecs": "ecs",
    "seed-tables": "seed_tables",
    "scaling": "scaling",
    "numerics": "numerics",
}

# In a checkout: the committed results folder; installed: ./bench-results
_RESULTS = Path(__file__).resolve().parent / "results"
DEFAULT_OUT = _RESULTS if _RESULTS.is_dir() else Path.cwd() / "bench-results"


def _usage_line() -> str:
    known = ", ".join(sorted(REGISTRY))
    return f"usage: python -m bench NAME [--quick] [--out DIR] [--machine SLUG]; known benchmarks: {known}"


def write_json(doc: dict[str, Any], path: Path) -> None:
    """Write atomically (a reader never sees half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(_usage_line(), file=sys.stderr if not argv else sys.stdout)
        return 2 if not argv else 0
    name = argv[0]
    if name not in REGISTRY:
        print(f"bench: unknown benchmark {name!r}; known benchmarks: {', '.join(sorted(REGISTRY))}", file=sys.stderr)
        return 2
    module = importlib.import_module(f"{__package__ or 'bench'}.{REGISTRY[name]}")

    parser = argparse.ArgumentParser(
        prog=f"python -m bench {name}", description=(module.__doc__ or "").strip().splitlines()[0]
    )
    parser.add_argument("--quick", action="store_true", help="tiny sizes: a smoke run in seconds")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output folder (default {DEFAULT_OUT})")
    parser.add_argument(
        "--machine", metavar="SLUG", default=None, help="machine slug used in the output file name (default: derived)"
    )
    if hasattr(module, "add_arguments"):
        module.add_arguments(parser)
    args = parser.parse_args(argv[1:])
    if args.machine is not None:
        try:
            check_slug(args.machine)
        except ValueError as exc:
            print(f"bench: {exc}", file=sys.stderr)
            return 2

    machine = describe(threads=getattr(module, "THREADS", 1), slug=args.machine)
    progress = Progress(name)
    progress.note(
        f"machine {machine['slug']}: {machine['cpu_model']}, {machine['cpu_affinity']} cores"
        + (f", {machine['gpu']['name']}" if machine["gpu"] else "")
    )
    doc = module.run(args, machine, progress)
    path = Path(args.out) / f"{name}-{machine['slug']}.json"
    write_json(doc, path)
    progress.note(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
