"""Acceleration structures on a device that traces rays: bottom levels per mesh, and the top level
built and updated over 10k, 100k and 1M instances (issue 18).

Bottom levels: the cube, a sphere, the torus knot (the demo model) and a 64k-triangle sphere,
each built alone and compacted: the build's GPU ms (timestamps around it), the wall ms of the
whole call (build, compacted-size query, copy), bytes before and after compaction. Top level,
per instance count: the CPU ms of writing the instance rows (render/raytracing/instances.py, the chunk
jobs' kernel: one thread, and split over the job pool), the GPU ms of a full build and of an
update (refit) after every instance moved; medians of `--repeat` runs each. Frames: the scaling
scene with one casting light (directional, spot, point) at 1280x720 on THREADS threads, drawn with
shadow maps (forward, and in the deferred form the rays use) and with ray-traced shadows.

JSON (schema_version 1): {"benchmark": "raytracing", "quick", "machine", "device", "config":
{"counts", "repeat", "threads"}, "bottom": [{"mesh", "triangles", "build_gpu_ms", "wall_ms",
"bytes", "compacted_bytes"}], "top": [{"instances", "write_ms_1_thread", "write_ms_threads",
"build_gpu_ms", "update_gpu_ms", "bytes"}], "frames": [{"entities", "light", "shadows",
"light_culling", "cpu_ms", "gpu_ms"}]}.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from ecs_engine.jobs import default_threads

COUNTS = (10_000, 100_000, 1_000_000)
QUICK_COUNTS = (1_000,)
THREADS = min(16, default_threads())


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--counts", type=int, nargs="+", help="instance counts (default 10k, 100k, 1M)")
    parser.add_argument("--repeat", type=int, default=9, help="runs of each measurement (default 9)")


def preflight(args: argparse.Namespace) -> None:
    if args.repeat < 1:
        raise ValueError(f"--repeat must be at least 1, got {args.repeat}")
    if args.counts and min(args.counts) < 1:
        raise ValueError("--counts must be positive")


class GpuTimer:
    """GPU ms of what `record(cb)` records, from two timestamps in one submit."""

    def __init__(self, device: Any) -> None:
        vk = device.vk
        self.device = device
        self.pool = vk.vkCreateQueryPool(
            device.handle, vk.VkQueryPoolCreateInfo(queryType=vk.VK_QUERY_TYPE_TIMESTAMP, queryCount=2), None
        )
        self.stamps = vk.ffi.new("uint64_t[2]")

    def time(self, record: Callable[[Any], Any]) -> float:
        vk, lib = self.device.vk, self.device.vk.lib

        def timed(cb: Any) -> None:
            lib.vkCmdResetQueryPool(cb, self.pool, 0, 2)
            lib.vkCmdWriteTimestamp(cb, vk.VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, self.pool, 0)
            record(cb)
            lib.vkCmdWriteTimestamp(cb, vk.VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, self.pool, 1)

        self.device.submit_once(timed)
        flags = vk.VK_QUERY_RESULT_64_BIT | vk.VK_QUERY_RESULT_WAIT_BIT
        lib.vkGetQueryPoolResults(self.device.handle, self.pool, 0, 2, 16, self.stamps, 8, flags)
        ticks = int(self.stamps[1]) - int(self.stamps[0])
        return ticks * self.device.info.timestamp_period_ns / 1e6

    def destroy(self) -> None:
        self.device.vk.vkDestroyQueryPool(self.device.handle, self.pool, None)


def _meshes(quick: bool) -> list[tuple[str, Any]]:
    from ecs_engine.render.assets.mesh_loading import DEFAULT_MODEL, load_mesh
    from ecs_engine.render.assets.primitives import cube_mesh, sphere_mesh

    meshes = [("cube", cube_mesh()), ("sphere 32x16", sphere_mesh())]
    if not quick:
        meshes += [("torus knot", load_mesh(DEFAULT_MODEL)), ("sphere 256x128", sphere_mesh(256, 128))]
    return meshes


def bottom_levels(device: Any, timer: GpuTimer, quick: bool, repeat: int, progress: Any) -> list[dict[str, Any]]:
    from ecs_engine.gpu import acceleration as acc
    from ecs_engine.render.assets.mesh_registry import MeshRegistry
    from ecs_engine.render.layouts import MESH_VERTEX

    out = []
    meshes = MeshRegistry(device)
    try:
        for name, data in _meshes(quick):
            with progress.step(f"bottom level: {name}"):
                mesh = meshes[meshes.add(data)]
                given = acc.MeshInput(
                    mesh.vertices, len(data.positions), MESH_VERTEX.itemsize, mesh.indices, mesh.index_count
                )
                walls: list[float] = []
                gpus: list[float] = []
                sizes = (0, 0)
                for _ in range(repeat):
                    t0 = time.perf_counter()
                    small = acc.build_bottom_levels(device, [given])
                    walls.append((time.perf_counter() - t0) * 1e3)
                    # the build alone, without compaction, between timestamps: GPU ms and full size
                    timed = acc.build_bottom_levels(
                        device, [given], compact=False, submit=lambda record, gpus=gpus: gpus.append(timer.time(record))
                    )
                    sizes = (timed[0].size, small[0].size)
                    for s in small + timed:
                        s.destroy()
                out.append(
                    {
                        "mesh": name,
                        "triangles": mesh.index_count // 3,
                        "build_gpu_ms": statistics.median(gpus),
                        "wall_ms": statistics.median(walls),
                        "bytes": sizes[0],
                        "compacted_bytes": sizes[1],
                    }
                )
    finally:
        meshes.destroy()
    return out


def _field(n: int, seed: int) -> np.ndarray:
    """n model matrices (n, 4, 4) float32: cubes spread over a field, turned and scaled."""
    rng = np.random.default_rng(seed)
    side = max(1.0, np.cbrt(n)) * 2.0
    model = np.zeros((n, 4, 4), dtype=np.float32)
    angle = rng.uniform(0, 2 * np.pi, n)
    c, s = np.cos(angle), np.sin(angle)
    scale = rng.uniform(0.5, 1.5, n)
    model[:, 0, 0], model[:, 0, 2], model[:, 2, 0], model[:, 2, 2] = c * scale, s * scale, -s * scale, c * scale
    model[:, 1, 1] = scale
    model[:, :3, 3] = rng.uniform(-side, side, (n, 3))
    model[:, 3, 3] = 1.0
    return model


def top_levels(
    device: Any, timer: GpuTimer, counts: tuple[int, ...], repeat: int, progress: Any
) -> list[dict[str, Any]]:
    from ecs_engine.jobs import JobPool
    from ecs_engine.render.assets.mesh_registry import MeshRegistry
    from ecs_engine.render.assets.primitives import cube_mesh

    out = []
    meshes = MeshRegistry(device)
    pool = JobPool(THREADS)
    try:
        cube = meshes.add(cube_mesh())
        blas = meshes.bottom_levels()
        for n in counts:
            with progress.step(f"top level: {n:,} instances"):
                out.append(_top_level(device, timer, pool, np.full(n, cube, dtype=np.int32), blas, repeat))
    finally:
        pool.close()
        meshes.destroy()
    return out


def _top_level(
    device: Any, timer: GpuTimer, pool: Any, handles: np.ndarray, blas: np.ndarray, repeat: int
) -> dict[str, Any]:
    """One instance count: rows written on one thread and over the pool, built, refitted."""
    from ecs_engine.gpu.acceleration import AS_INSTANCE, TopLevel
    from ecs_engine.gpu.memory import UPLOAD, Buffer
    from ecs_engine.render.raytracing.instances import write_instances

    lib = device.vk.lib
    n = len(handles)
    models = [_field(n, 1), _field(n, 2)]
    usage = (
        lib.VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT
        | lib.VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR
    )
    rows_buffer = Buffer(device, n * AS_INSTANCE.itemsize, usage, UPLOAD)
    top = TopLevel(device, n)
    try:
        rows = rows_buffer.array(AS_INSTANCE, n)
        spans = [slice(i, min(i + 4096, n)) for i in range(0, n, 4096)]  # the render chunks' size

        def write(model: np.ndarray, span: slice) -> None:
            write_instances(model[span], handles[span], blas, span.start, True, rows[span])

        def build(update: bool, cb: Any) -> None:
            refits.append(top.record(cb, rows_buffer.address, n, update=update))

        one: list[float] = []
        many: list[float] = []
        builds: list[float] = []
        updates: list[float] = []
        refits: list[bool] = []
        for r in range(repeat):
            model = models[r % 2]
            t0 = time.perf_counter()
            write(model, slice(0, n))
            one.append((time.perf_counter() - t0) * 1e3)
            t0 = time.perf_counter()
            pool.map(partial(write, model), spans)
            many.append((time.perf_counter() - t0) * 1e3)
            builds.append(timer.time(partial(build, False)))
            write(models[(r + 1) % 2], slice(0, n))  # every instance moved
            updates.append(timer.time(partial(build, True)))
        assert refits == [False, True] * repeat, "the updates were not refits"
        return {
            "instances": n,
            "write_ms_1_thread": statistics.median(one),
            "write_ms_threads": statistics.median(many),
            "build_gpu_ms": statistics.median(builds),
            "update_gpu_ms": statistics.median(updates),
            "bytes": top.structure.size if top.structure is not None else 0,
        }
    finally:
        top.destroy()
        rows_buffer.destroy()


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    from ecs_engine.app.report import describe_device
    from ecs_engine.errors import UsageError
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance

    counts = tuple(args.counts or (QUICK_COUNTS if args.quick else COUNTS))
    repeat = 2 if args.quick else args.repeat
    instance = Instance()
    try:
        device = Device(instance)
        try:
            if device.ray_tracing is None:
                raise UsageError(
                    f"{device.info.name} has no ray-tracing pipelines (VK_KHR_ray_tracing_pipeline): nothing to measure"
                )
            timer = GpuTimer(device)
            try:
                bottom = bottom_levels(device, timer, args.quick, repeat, progress)
                top = top_levels(device, timer, counts, repeat, progress)
            finally:
                timer.destroy()
            described = describe_device(device)
        finally:
            device.destroy()
    finally:
        instance.destroy()
    framed = frames(counts, args.quick, progress)  # a device of their own (bench.headless_gpu)
    print(f"{'mesh':16} {'triangles':>9} {'build GPU ms':>12} {'wall ms':>8} {'MB':>7} {'compacted MB':>12}")
    for b in bottom:
        print(
            f"{b['mesh']:16} {b['triangles']:9,} {b['build_gpu_ms']:12.3f} {b['wall_ms']:8.2f} "
            f"{b['bytes'] / 2**20:7.2f} {b['compacted_bytes'] / 2**20:12.2f}"
        )
    print(
        f"{'instances':>9} {'write ms 1t':>11} {f'write ms {THREADS}t':>12} "
        f"{'build GPU ms':>12} {'update GPU ms':>13} {'MB':>7}"
    )
    for t in top:
        print(
            f"{t['instances']:9,} {t['write_ms_1_thread']:11.2f} {t['write_ms_threads']:12.2f} "
            f"{t['build_gpu_ms']:12.3f} {t['update_gpu_ms']:13.3f} {t['bytes'] / 2**20:7.1f}"
        )
    print(
        f"frames at {FRAME_SIZE[0]}x{FRAME_SIZE[1]}, {THREADS} threads: CPU ms / GPU ms "
        "(the smaller of 2 runs' medians)"
    )
    for f in framed:
        gpu_ms = "-" if f["gpu_ms"] is None else f"{f['gpu_ms']:.2f}"
        print(
            f"{f['entities']:>9,} {f['light']:>12} {f['shadows']:>9} ({f['light_culling']:>8}) "
            f"{f['cpu_ms']:8.2f} / {gpu_ms}"
        )
    return {
        "benchmark": "raytracing",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": described,
        "config": {"counts": list(counts), "repeat": repeat, "threads": THREADS},
        "bottom": bottom,
        "top": top,
        "frames": framed,
    }


FRAME_LIGHTS = ("directional", "spot", "point")
FRAME_METHODS = (("maps", "auto"), ("maps", "deferred"), ("raytraced", "auto"))  # (shadows, light culling)
FRAME_SIZE = (1280, 720)


def frames(counts: tuple[int, ...], quick: bool, progress: Any) -> list[dict[str, Any]]:
    """The scaling scene (moving, spinning cubes) with one casting light, drawn with shadow maps
    (the forward form, and the deferred one the rays need) and ray-traced: CPU and GPU ms, the
    smaller of two runs' medians, the configurations of a count alternated."""
    from . import headless_gpu

    warmup, timed = (2, 4) if quick else (8, 30)
    runs: dict[tuple[int, str, str, str], list[dict[str, Any]]] = {}
    with headless_gpu(*FRAME_SIZE) as gpu:
        for n in counts:
            for round_ in range(2):
                configs = [(light, *m) for light in FRAME_LIGHTS for m in FRAME_METHODS]
                for light, method, culling in configs if round_ == 0 else configs[::-1]:
                    with progress.step(f"frames: {n:,} entities, {light}, {method} ({culling}), run {round_ + 1}"):
                        runs.setdefault((n, light, method, culling), []).append(
                            _frame(gpu, n, light, method, culling, warmup, timed)
                        )
    out = []
    for (n, light, method, culling), measured in runs.items():
        gpu_ms = [m["gpu_ms"] for m in measured if m["gpu_ms"] is not None]
        out.append(
            {
                "entities": n,
                "light": light,
                "shadows": method,
                "light_culling": culling,
                "cpu_ms": min(m["cpu_ms"] for m in measured),
                "gpu_ms": min(gpu_ms) if gpu_ms else None,
            }
        )
    return out


def _frame(gpu: Any, n: int, light: str, method: str, culling: str, warmup: int, timed: int) -> dict[str, Any]:
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.ecs.world import World
    from ecs_engine.jobs import JobPool
    from ecs_engine.render.frame.renderer import Renderer

    from . import timed_frames
    from .shadows import add_light

    device, target, meshes = gpu
    world = World()
    scene_builder("scaling", n)(world, meshes.add)
    add_light(world, light, "pcf")
    with JobPool(THREADS) as pool:
        world.resources[JobPool] = pool
        renderer = Renderer(device, target, meshes, jobs=pool, shadows=method, light_culling=culling)
        try:
            return timed_frames(world, default_schedule(), renderer, warmup, timed)
        finally:
            renderer.destroy()
