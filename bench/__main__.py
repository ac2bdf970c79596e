"""`ecs-engine bench NAME [--quick] [--out DIR] [--machine SLUG]`, or `python -m ecs_engine.bench ...`
(both work from any folder; `python -m bench` only inside the checkout).

Runs one registered benchmark, prints its table on stdout (progress goes to stderr) and writes
`<out>/<NAME>-<slug>.json` with its plot beside it. The default out is a folder in the user's cache
(`default_out()`), so a run never changes a checkout; `--out bench/results` updates the committed
results. Exit codes: 0 done (or --help), 2 usage error: a bad argument, or a benchmark that cannot
run here (its `preflight(args)`, called before anything is printed, or its run raised UsageError: a
missing optional extra, no GPU), reported as one line.
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
    "soak": "soak",
    "lights": "lights",
    "shadows": "shadows",
    "schedule": "schedule",
    "scene-io": "scene_io",
    "hierarchy": "hierarchy",
    "culling": "culling",
    "culling-methods": "culling_methods",
    "frame": "frame",
    "bytecodes": "bytecodes",
    "peers": "peers",
    "raytracing": "raytracing",
    "lod-build": "lod_build",
    "gpu-memory": "gpu_memory",
    "physics-libs": "physics_libs",
    "physics": "physics",
    "animation": "animation",
    "audio": "audio",
}

# One line each for the list in the usage text (the modules are not imported to print it).
SUMMARY: dict[str, str] = {
    "ecs": "ECS queries, spawns and transform frames: ecs_engine against esper (CPU only)",
    "seed-tables": "the seed's three scenes headless, beside the seed's Tables 4.1-4.3 (Vulkan)",
    "scaling": "render-job scaling by entities, threads, mode and recorder (Vulkan)",
    "numerics": "spring integrators' error against run time, render precision against distance",
    "soak": "the editor's scene for 100,000 frames with churn and settings switches: memory flat? (Vulkan)",
    "lights": "GPU ms against light count (1 to 16,384), every light per fragment vs clustered (Vulkan)",
    "shadows": "CPU and GPU ms of each light type and filter casting, 10k to 1M entities, 1 and 16 threads (Vulkan)",
    "schedule": "the parallel schedule: 8 independent systems over 1M entities, 1 to 16 threads (CPU only)",
    "scene-io": "World.save and World.load of the scaling scene, 10k to 1M entities (CPU only)",
    "hierarchy": "HierarchySystem over 11k to 1.1M entities with Parent, plan kept and made again (CPU only)",
    "culling": "temporal-coherence culling against per-frame frustum culling over camera paths, 10k to 1M (CPU only)",
    "culling-methods": "CPU, GPU and wall ms of every culling method, moving scene at 1280x720, 10k to 1M (Vulkan)",
    "frame": "one scene's CPU frame through the run loop, median and p99 (default: 1 cube, 2,400 frames) (Vulkan)",
    "bytecodes": "Python bytecodes a scene's frame runs, by module: a count the host's speed does not move (Vulkan)",
    "peers": "the scaling workload here and in pygfx, wall ms a frame side by side, 1k to 1M (Vulkan, wgpu)",
    "raytracing": "bottom levels per mesh, top-level build and update at 10k to 1M instances (Vulkan ray tracing)",
    "lod-build": "time and peak memory of building levels of detail, 16k to 263k vertices (CPU only)",
    "gpu-memory": "device memory of the renderer's images per render configuration at 1280x720 (Vulkan)",
    "physics-libs": "rigid-body libraries (rapier3d, culverin, pybullet): a 10k pile, 100k statics, rays (CPU only)",
    "physics": "the engine's physics: what it adds to Jolt's step at a 10k pile and 100k statics, 10k rays (CPU only)",
    "animation": "a crowd of skinned characters playing clips: CPU, GPU and per-system ms at 1k and 10k (Vulkan)",
    "audio": "mixing 1,000 moving spatial sources at 48 kHz: CPU ms per 10 ms of sound; one-shot latency (CPU only)",
}

# The commands that work from any folder once ecs_engine is installed.
COMMANDS = ("ecs-engine bench", "python -m ecs_engine.bench")
OPTIONS = "NAME [--quick] [--out DIR] [--machine SLUG]"


def default_out() -> Path:
    """The user's cache, never the package folder: a quick run must leave a checkout unchanged."""
    from ecs_engine.user_dirs import cache_home

    try:
        return cache_home() / "ecs_engine" / "bench-results"
    except RuntimeError:  # no home directory to be found
        return Path.cwd() / "bench-results"


def usage() -> str:
    """The usage lines, the benchmarks and where results go (what --help and a bare call print)."""
    width = max(map(len, REGISTRY))
    names = "\n".join(f"  {name:{width}}  {SUMMARY.get(name, '')}".rstrip() for name in sorted(REGISTRY))
    return (
        f"usage: {COMMANDS[0]} {OPTIONS}\n   or: {COMMANDS[1]} {OPTIONS}\n\n"
        f"benchmarks:\n{names}\n\n"
        f"Writes <out>/NAME-<machine>.json and its plot; out defaults to {default_out()}\n"
        "(--out bench/results in a checkout updates the committed results).\n"
        f"`{COMMANDS[0]} NAME --help` lists a benchmark's own options."
    )


def write_json(doc: dict[str, Any], path: Path) -> None:
    """Write atomically (a reader never sees half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def main(argv: list[str] | None = None, prog: str = COMMANDS[1]) -> int:
    """Run one benchmark; `prog` is the command named in its --help (the CLI passes its own).
    Ctrl-C is one line and exit 130, a closed stdout (`| head`) a quiet end (entry_point.py)."""
    from ecs_engine.app.entry_point import run_command

    return run_command(prog, lambda: run_benchmark(argv, prog))


def run_benchmark(argv: list[str] | None, prog: str) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] in (["-h"], ["--help"]):
        print(usage())
        return 0
    if not argv:
        print(usage(), file=sys.stderr)
        return 2
    name = argv[0]
    known = ", ".join(sorted(REGISTRY))
    if name.startswith("-"):
        print(f"bench: the benchmark name comes first ({COMMANDS[0]} {OPTIONS}); known: {known}", file=sys.stderr)
        return 2
    if name not in REGISTRY:
        print(f"bench: unknown benchmark {name!r}; known benchmarks: {known}", file=sys.stderr)
        return 2
    module = importlib.import_module(f"{__package__ or 'bench'}.{REGISTRY[name]}")
    from ecs_engine.errors import UsageError  # here: the usage text above needs no ecs_engine

    out = default_out()
    parser = argparse.ArgumentParser(prog=f"{prog} {name}", description=(module.__doc__ or "").strip().splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="tiny sizes: a smoke run in seconds")
    parser.add_argument(
        "--out",
        type=Path,
        default=out,
        metavar="DIR",
        help=f"output folder (default {out}; --out bench/results updates the committed results)",
    )
    parser.add_argument(
        "--machine", metavar="SLUG", default=None, help="machine slug used in the output file name (default: derived)"
    )
    if hasattr(module, "add_arguments"):
        module.add_arguments(parser)
    args = parser.parse_args(argv[1:])
    try:
        if args.machine is not None:
            check_slug(args.machine)
        if hasattr(module, "preflight"):
            module.preflight(args)
    except (ValueError, UsageError) as exc:
        print(f"bench: {exc}", file=sys.stderr)
        return 2

    machine = describe(threads=getattr(module, "THREADS", 1), slug=args.machine)
    progress = Progress(name)
    progress.note(
        f"machine {machine['slug']}: {machine['cpu_model']}, {machine['cpu_affinity']} cores"
        + (f", {machine['gpu']['name']}" if machine["gpu"] else "")
    )
    progress.note(f"results go to {Path(args.out).resolve()}")
    try:
        doc = module.run(args, machine, progress)
    except UsageError as exc:  # e.g. no Vulkan device
        print(f"bench: {exc}", file=sys.stderr)
        return 2
    if doc is None:  # the benchmark only redrew an earlier result (culling --plot)
        return 0
    path = Path(args.out) / f"{name}-{machine['slug']}.json"
    write_json(doc, path)
    progress.note(f"wrote {path.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
