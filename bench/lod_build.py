"""Levels of detail: time and peak memory of build_lods at 16k to 1M vertices (CPU only).

Each size runs in a fresh child process, so its peak resident memory (VmHWM: getrusage's
ru_maxrss would carry the parent's across exec) is its own: the child makes the mesh, notes its
peak, builds the levels and reports the time, the peak's growth per vertex, and each level's
triangles and error. The meshes are UV spheres (the scene-file recipe of issue 34,
`{"primitive": "sphere", "args": {"segments": n, "rings": n}}`) and the torus knot the `model`
demo draws. The target (docs/performance.md): a few hundred bytes a vertex and time linear in the
vertices, as meshoptimizer-class tools cost.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from typing import Any

SIZES = (128, 256, 512)  # sphere segments = rings: 16,641, 66,049 and 263,169 vertices

_CHILD = """
import json, sys, time
from ecs_engine.render.assets.mesh_loading import DEFAULT_MODEL, load_mesh
from ecs_engine.render.assets.mesh_lod import build_lods
from ecs_engine.render.assets.primitives import sphere_mesh
n = int(sys.argv[1])
mesh = sphere_mesh(n, n) if n else load_mesh(DEFAULT_MODEL)
def peak():
    return next(int(line.split()[1]) * 1024 for line in open("/proc/self/status") if line.startswith("VmHWM:"))
build_lods(sphere_mesh(16, 8), min_triangles=8)  # compile the kernels (cached on disk) outside the timing
before = peak()
start, cpu = time.perf_counter(), time.process_time()
lods = build_lods(mesh)
seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
print(json.dumps({"mesh": mesh.name, "vertices": mesh.vertex_count, "triangles": mesh.triangle_count,
                  "seconds": seconds, "cpu_seconds": cpu, "peak_growth_bytes": peak() - before,
                  "levels": [[lod.mesh.triangle_count, lod.error] for lod in lods]}))
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="sphere segments (= rings)")


def measure(n: int) -> dict[str, Any]:
    """One build in a child process: n sphere segments, or 0 for the torus knot."""
    done = subprocess.run([sys.executable, "-c", _CHILD, str(n)], capture_output=True, text=True, check=True)
    row: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    row["bytes_per_vertex"] = row["peak_growth_bytes"] / row["vertices"]
    row["cpu_us_per_vertex"] = 1e6 * row["cpu_seconds"] / row["vertices"]
    return row


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    sizes = [32, 64] if args.quick else args.sizes
    rows = []
    for n in [0, *sizes]:
        with progress.step("torus knot" if n == 0 else f"sphere {n}x{n}"):
            rows.append(measure(n))
    header = f"{'mesh':>12} {'vertices':>10} {'wall s':>7} {'CPU s':>6} {'CPU us/vertex':>14} {'bytes/vertex':>13}"
    print(header + "  levels")
    for r in rows:
        levels = ", ".join(f"{t:,}" for t, _ in r["levels"])
        print(
            f"{r['mesh']:>12} {r['vertices']:>10,} {r['seconds']:>7.2f} {r['cpu_seconds']:>6.2f}"
            f" {r['cpu_us_per_vertex']:>14.1f} {r['bytes_per_vertex']:>13,.0f}  {levels}"
        )
    return {"benchmark": "lod-build", "machine": machine, "quick": bool(args.quick), "rows": rows}
