"""The bound docs/scene-format.md states (issue 34): a scene or model file under 10 MB loads, or is
refused with one clear error, within 10 s of CPU time and 2 GB. Each file is opened in a child
process whose resident memory and CPU time are watched (and which is stopped past the bound, so a
regression fails here instead of taking the machine's memory). CPU time on one thread, counted
from when the child has imported the engine and compiled its kernels, not wall time: on a CI box
shared with other jobs the wall clock ran 2.5 times the CPU time; a wall-clock watchdog of
`WALL` seconds still stops a child that waits on nothing. The files: the scene with the issue's
hostile recipe entries (a 1M-vertex sphere, eight of them), one with the largest recipe the cap
lets through, a 10 MB OBJ and an OBJ of one 100k-triangle fan (the simplifier's time grows with
the square of a vertex's triangles), each loaded and given its levels of detail as the indirect
mode's first frame would."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import zipfile

import numpy as np
import psutil
import pytest

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.ecs.scene_file import save_world
from ecs_engine.render.assets.primitives import sphere_mesh
from ecs_engine.render.assets.scene_assets import scene_codecs

SECONDS, BYTES, WALL = 10.0, 2 << 30, 90.0

_OPEN = """
import sys, time
path = sys.argv[1]
# the levels' kernels compiled (numba, cached on disk after the first run) before the clock: the
# bound is on what the file asks for, not on the engine's one-time start
from ecs_engine.render.assets.mesh_lod import build_lods
from ecs_engine.render.assets.primitives import sphere_mesh
build_lods(sphere_mesh(16, 8), min_triangles=8)
start = time.process_time()
print("ready", flush=True)
try:
    if path.endswith(".obj"):
        from ecs_engine.render.assets.mesh_loading import load_mesh
        mesh = load_mesh(path)
        print("loaded", mesh.vertex_count, "vertices,", len(build_lods(mesh)), "levels")
    else:
        from ecs_engine import World
        from ecs_engine.ecs.scene_file import load_world
        from ecs_engine.render.assets.scene_assets import scene_codecs
        class Registry(list):
            def add(self, mesh):
                self.append(mesh)
                return len(self) - 1
        load_world(path, World(), resources=scene_codecs(Registry()))
        print("loaded")
except ValueError as exc:  # SceneFileError, UsageError: the one clear refusal
    print("refused:", exc)
# VmHWM, not ru_maxrss: Linux keeps ru_maxrss across exec, so a child of a big test process would
# report its parent's size; the high-water mark belongs to this process's own memory map
hwm = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print("cpu", time.process_time() - start, "peak", hwm * 1024)
"""


class Registry(list):
    def add(self, mesh):
        self.append(mesh)
        return len(self) - 1


# One core's worth: numba, NumPy and OpenBLAS threads would add their spinning to the process's
# CPU time on a many-core host (the H200 host's 16 cores took the 10 MB OBJ past 10 s of CPU)
ONE_THREAD = {name: "1" for name in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}


def open_bounded(path) -> tuple[str, float, int]:
    """Open `path` in a child: its output, CPU seconds (from when it is ready) and peak resident
    bytes; stopped (and failed) past the bound."""
    start = time.perf_counter()
    child = subprocess.Popen(
        [sys.executable, "-c", _OPEN, str(path)], stdout=subprocess.PIPE, text=True, env={**os.environ, **ONE_THREAD}
    )
    assert child.stdout is not None
    assert child.stdout.readline() == "ready\n"  # imported, kernels compiled: the clock starts
    watched, peak = psutil.Process(child.pid), 0
    times = watched.cpu_times()
    ready, seconds = times.user + times.system, 0.0
    while child.poll() is None:
        try:
            peak = max(peak, watched.memory_info().rss)
            times = watched.cpu_times()
            seconds = times.user + times.system - ready
        except psutil.NoSuchProcess:
            break
        if peak > BYTES or seconds > SECONDS or time.perf_counter() - start > WALL:
            child.kill()
            child.wait()
            pytest.fail(f"{path.name}: past the bound ({peak / 2**20:.0f} MiB, {seconds:.1f} s of CPU)")
        time.sleep(0.02)
    out = child.stdout.read()
    assert child.returncode == 0, out
    peak = max(peak, int(out.rsplit("peak", 1)[1]))
    seconds = max(seconds, float(out.rsplit("cpu", 1)[1].split()[0]))
    return out, seconds, peak


def hostile_scene(path, sizes) -> None:
    """A small saved scene plus one meshes-resource entry per sphere size, used by no entity."""
    world = World()
    world.spawn(Transform(), Mesh(handle=0))
    save_world(world, path, resources=scene_codecs(Registry([sphere_mesh(8, 4)])))
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    header = json.loads(members.pop("header.json"))
    meshes = next(r for r in header["resources"] if r["name"] == "meshes")
    for k, n in enumerate(sizes):
        source = {"primitive": "sphere", "args": {"segments": n, "rings": n}}
        meshes["doc"]["meshes"].append({"handle": 1 + k, "vertices": (n + 1) ** 2, "source": source})
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("header.json", json.dumps(header))
        for name, data in members.items():
            archive.writestr(name, data)


def obj_of(path, mesh, size: int) -> None:
    """`mesh` as an OBJ of positions and faces, padded with comments to `size` bytes."""
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in mesh.positions.tolist()]
    lines += [f"f {a} {b} {c}" for a, b, c in (mesh.indices.reshape(-1, 3) + 1).tolist()]
    text = "\n".join(lines) + "\n"
    assert len(text) <= size
    path.write_text(text + "#" * (size - len(text) - 1) + "\n")


@pytest.mark.parametrize(
    ("name", "sizes", "expect"),
    [
        ("issue", [1024], "refused: .*1,050,625 vertices"),
        ("eight", [1024 - k for k in range(8)], "refused: .*at most 262,144"),
        ("largest", [500], "loaded"),
    ],
)
def test_a_hostile_scene_loads_or_is_refused_within_the_bound(tmp_path, name, sizes, expect):
    path = tmp_path / f"{name}.scene"
    hostile_scene(path, sizes)
    assert path.stat().st_size < 10 << 20
    out, seconds, peak = open_bounded(path)
    assert __import__("re").search(expect, out), out
    assert seconds < SECONDS and peak < BYTES


def test_a_10_mb_model_loads_with_its_levels_within_the_bound(tmp_path):
    path = tmp_path / "big.obj"
    obj_of(path, sphere_mesh(340, 340), (10 << 20) - 1)
    out, seconds, peak = open_bounded(path)
    assert out.startswith("loaded") and " 0 levels" not in out, out
    assert seconds < SECONDS and peak < BYTES


def test_a_fan_model_is_drawn_without_levels_within_the_bound(tmp_path):
    n = 100_000
    angle = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    lines = ["v 0 0 0"] + [f"v {np.cos(a):.6f} {np.sin(a):.6f} 0" for a in angle.tolist()]
    lines += [f"f 1 {2 + i} {2 + (i + 1) % n}" for i in range(n)]
    path = tmp_path / "fan.obj"
    path.write_text("\n".join(lines) + "\n")
    assert path.stat().st_size < 10 << 20
    out, seconds, peak = open_bounded(path)
    assert out.startswith("loaded 100001 vertices, 0 levels"), out
    assert seconds < SECONDS and peak < BYTES
