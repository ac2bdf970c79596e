"""Running a scene: world and schedule, the Vulkan objects it needs, the frame loop, the summary.

Headless runs render into an offscreen image (no window, surface or swapchain, no display
needed) with a fixed time step, so a run is reproducible frame for frame.
"""

from __future__ import annotations

import importlib
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import UsageError
from ..ecs.schedule import Schedule
from ..ecs.world import World

SCENES = ("cube", "grid100", "model", "scaling")
FIXED_DT = 1.0 / 60.0


@dataclass
class RunOptions:
    scene: str = "grid100"
    path: str | None = None
    headless: bool = True
    frames: int | None = None  # None: until the window closes (headless: 1)
    screenshot: str | None = None
    width: int = 1280
    height: int = 720
    validate: bool = False
    present: str = "fifo"
    quiet: bool = False
    mode: str = "instanced"  # instanced | per_entity | indirect
    threads: int | None = None  # worker pool size, counting the main thread (None: all cores)
    culling: bool = True
    chunk_rows: int | None = None  # rows per render job (None: about one per thread, renderer.MIN_CHUNK_ROWS)
    recorder: str | None = None  # native | python (None: native when numba is there)
    entities: int = 10_000  # the scaling scene's entity count
    perf_json: str | None = None  # write every frame's perf samples here at the end
    editor: bool = False  # the ImGui editor and Perf window (headless: drawn into the image)
    scenes: tuple[str, ...] = ("cube", "grid100", "model")  # the editor's scene switcher


@dataclass
class RunResult:
    frames: int = 0
    wall_s: float = 0.0
    cpu_ms: list[float] = field(default_factory=list)  # frame start to submit, minus waits for the GPU
    gpu_ms: list[float] = field(default_factory=list)
    frame_end: list[float] = field(default_factory=list)  # perf_counter() after each frame's submit
    record_ms: list[float] = field(default_factory=list)  # the render jobs of each frame
    ui_ms: list[float] = field(default_factory=list)  # the editor's own CPU time per frame (editor runs)
    validation_messages: list[str] = field(default_factory=list)
    device: str = ""
    pixels: np.ndarray | None = None
    last_stats: Any = None
    perf: Any = None  # the run's perf.PerfMonitor
    editor: Any = None  # the run's editor_session.EditorSession, while it runs
    recreations: int = 0  # swapchain recreations (windowed)
    minimised_waits: int = 0  # loop turns spent waiting while minimised (windowed)

    @property
    def fps(self) -> float:
        return self.frames / self.wall_s if self.wall_s > 0 else 0.0

    def add_frame(self, stats: Any, cpu_ms: float, end: float, waited_ms: float = 0.0,
                  ui_ms: float | None = None) -> None:
        """One frame's figures, into the lists and the perf monitor. `waited_ms`: time blocked
        outside the renderer (the swapchain), on top of `stats.wait_ms`."""
        self.cpu_ms.append(cpu_ms)
        self.frame_end.append(end)
        self.record_ms.append(stats.record_ms)
        if stats.gpu_ms is not None:
            self.gpu_ms.append(stats.gpu_ms)
        if ui_ms is not None:
            self.ui_ms.append(ui_ms)
        self.last_stats = stats
        self.perf.frame(cpu_ms, stats.record_ms, stats.gpu_ms, stats.wait_ms + waited_ms, draws=stats.draws,
                        visible=stats.instances)

    def write_perf_json(self, options: RunOptions, say: Callable[[str], None]) -> None:
        """`--perf-json`: every frame's samples, with what the run was."""
        if options.perf_json:
            self.perf.write_json(meta=run_meta(options, self))
            say(f"wrote {options.perf_json}")

    def record_ms_mean(self, warmup: int = 0) -> float:
        values = self.record_ms[warmup:] or self.record_ms
        return float(np.mean(values)) if values else 0.0

    def fps_after(self, warmup: int) -> float:
        """Frames per second of wall clock over the frames after the first `warmup`."""
        if warmup < 1 or len(self.frame_end) <= warmup:
            return self.fps
        return (len(self.frame_end) - warmup) / (self.frame_end[-1] - self.frame_end[warmup - 1])


def scene_builder(name: str, entities: int = 10_000) -> Callable[..., None]:
    if name not in SCENES:
        raise UsageError(f"unknown scene {name!r}; scenes: {', '.join(SCENES)}")
    build = importlib.import_module(f"ecs_engine.demos.{name}").build
    if name == "scaling":
        return lambda world, add_mesh, path=None: build(world, add_mesh, path, entities=entities)
    return build


def default_schedule() -> Schedule:
    """Simulation (orbits, motion, springs) in the fixed-step stage, the camera per frame, then
    render origin and matrices. `Schedule.run` runs every stage once; the frame loops use
    `Schedule.run_frame` with a FixedTimestep."""
    from ..systems import FlyCameraSystem, MotionSystem, OrbitSystem, RenderOriginSystem, SnapshotSystem, SpringSystem, TransformSystem

    schedule = Schedule(("fixed", "update", "post_update"))
    schedule.add(SnapshotSystem(), "fixed")  # first: what each step starts from, for interpolation
    schedule.add(OrbitSystem(), "fixed")
    schedule.add(MotionSystem(), "fixed")
    schedule.add(SpringSystem(), "fixed")
    schedule.add(FlyCameraSystem(), "update")
    schedule.add(RenderOriginSystem(), "post_update")
    schedule.add(TransformSystem(), "post_update")
    return schedule


def has_lights(world: World) -> bool:
    from ..components import PointLight

    return world.query(PointLight, write=()).count() > 0


def run(options: RunOptions, log: Callable[[str], None] | None = None) -> RunResult:
    """Build the scene and run it; headless only here (the window path lives in window.py)."""
    from .editor_session import EditorSession, SceneState
    from ..gpu.device import Device
    from ..gpu.instance import Instance
    from ..gpu.offscreen import OffscreenTarget
    from ..jobs import default_threads
    from ..render.mesh_registry import MeshRegistry
    from .perf import PerfMonitor
    from ..ecs.timestep import FixedTimestep

    say = log or (lambda text: None if options.quiet else print(text))
    build = scene_builder(options.scene, options.entities)
    result = RunResult()
    perf = result.perf = PerfMonitor(log=options.perf_json or False)
    instance = device = target = meshes = state = session = None
    jobs = job_pool(options)
    try:
        instance = Instance(validate=options.validate)
        device = Device(instance)
        result.device = describe_device(device)
        target = OffscreenTarget(device, options.width, options.height)
        meshes = MeshRegistry(device)
        world, schedule, renderer = build_scene(options, build, device, target, meshes, jobs)
        state = SceneState(options, world, schedule, renderer, jobs, device, target, meshes)
        if options.editor:
            session = result.editor = EditorSession(state, options.scenes, default_threads(),
                                                    len(renderer.frames.frames))
        frames = options.frames or 1
        clock = FixedTimestep(FIXED_DT)  # one step a frame: a headless run is reproducible
        say(f"{options.scene}: headless {options.width}x{options.height} on {result.device}, {frames} frames, "
            f"mode {options.mode}, {recorder_words(renderer)}, {jobs.threads} threads")
        start = time.perf_counter()
        for i in range(frames):
            t0 = time.perf_counter()
            state.schedule.run_frame(state.world, FIXED_DT, clock)
            if session is not None:
                session.build(state, result.last_stats, perf, FIXED_DT, options.width, options.height)
            last = i == frames - 1
            stats = state.renderer.render(state.world, readback=last and options.screenshot is not None)
            now = time.perf_counter()
            # CPU work, not waiting for the GPU
            result.add_frame(stats, (now - t0) * 1e3 - stats.wait_ms, now,
                             ui_ms=session.cost_ms if session is not None else None)
            if perf.summary_due():
                say(perf.summary_line())
            if session is not None and not last:
                session.apply_requests(state)
        device.wait_idle()
        result.frames = frames
        result.wall_s = time.perf_counter() - start
        if options.screenshot is not None:
            result.pixels = target.pixels()
            save_png(result.pixels, options.screenshot)
        say(summary_line(result, frames, result.wall_s, final=True))
        result.write_perf_json(options, say)
    finally:
        if session is not None:
            session.destroy()
        for obj in (state.renderer if state else None, meshes, target, device):
            if obj is not None:
                obj.destroy()
        if instance is not None:
            instance.destroy()
            result.validation_messages = list(instance.messages)
        (state.jobs if state else jobs).close()
    return result


def run_meta(options: RunOptions, result: RunResult) -> dict[str, Any]:
    """What a --perf-json file says about its run."""
    from ..jobs import default_threads

    return {"scene": options.scene, "mode": options.mode, "threads": options.threads or default_threads(),
            "culling": options.culling, "width": options.width, "height": options.height,
            "headless": options.headless, "device": result.device, "frames": result.frames,
            "wall_s": result.wall_s, "editor": options.editor}


def describe_device(device: Any) -> str:
    return f"{device.info.name} ({device.info.driver_name} {device.info.driver_info})".strip()


def build_scene(options: RunOptions, build: Callable[..., None], device: Any, target: Any, meshes: Any,
                jobs: Any) -> tuple[World, Schedule, Any]:
    """The scene's world (sharing the run's worker pool), its schedule, and a renderer that
    builds only what the scene needs."""
    from ..render.renderer import Renderer

    world = World()
    world.resources[type(jobs)] = jobs
    build(world, meshes.add, options.path)
    renderer = Renderer(device, target, meshes, mode=options.mode, jobs=jobs,
                        culling=options.culling, chunk_rows=options.chunk_rows, recorder=recorder_for(options))
    return world, default_schedule(), renderer


def recorder_words(renderer: Any) -> str:
    if renderer.mode == "indirect":
        return "commands written on the GPU"  # the recorder choice does not apply
    return f"{renderer.recorder} recorder"


def recorder_for(options: RunOptions) -> str:
    from .. import native

    if options.recorder is None:
        return "native" if native.AVAILABLE else "python"
    if options.recorder == "native" and not native.AVAILABLE:
        raise UsageError("the native recorder needs numba (pip install numba, and unset ECS_ENGINE_NO_NUMBA); "
                         "or use --recorder python")
    return options.recorder


def job_pool(options: RunOptions) -> Any:
    """The run's worker pool (also given to the world, so the stock systems split large tables)."""
    from ..jobs import JobPool

    return JobPool(options.threads)


WARMUP_FRAMES = 5  # left out of the closing summary: pipeline creation and JIT compiles land there


def summary_line(result: RunResult, frames: int, wall_s: float, final: bool = False) -> str:
    """Means over the last 600 frames; the closing line leaves out the warm-up frames (when
    there are enough frames) and gives their wall-clock rate."""
    skip = WARMUP_FRAMES if final and frames > 2 * WARMUP_FRAMES else 0
    cpu = np.array(result.cpu_ms[skip:][-600:])
    gpu = np.array(result.gpu_ms[skip:][-600:])
    stats = result.last_stats
    gpu_text = f"gpu {gpu.mean():.3f} ms" if len(gpu) else "gpu n/a"
    record = np.array(result.record_ms[skip:][-600:])
    if skip:
        frames, wall_s = frames - skip, result.frame_end[-1] - result.frame_end[skip - 1]
    label = f"{frames} frames after {skip} warm-up" if skip else f"frame {frames}"
    return (f"{label}: {frames / wall_s if wall_s > 0 else 0:.0f} fps (wall clock), cpu {cpu.mean():.3f} ms "
            f"(p99 {np.percentile(cpu, 99):.3f}, record {record.mean():.3f}), {gpu_text}; "
            f"{stats.instances} of {stats.candidates} entities "
            f"drawn in {stats.draws} draws, {stats.triangles} triangles, {stats.lights} lights")


def save_png(pixels: np.ndarray, path: str) -> None:
    from PIL import Image

    out = Path(path)
    if out.parent and not out.parent.exists():
        raise UsageError(f"cannot write {path}: folder {out.parent} does not exist")
    try:
        Image.fromarray(pixels, "RGBA").convert("RGB").save(out)
    except OSError as exc:
        raise UsageError(f"cannot write {path}: {exc.strerror or exc}") from exc


def report_validation(result: RunResult) -> int:
    """Print validation messages; non-zero when there were any."""
    if not result.validation_messages:
        return 0
    for message in result.validation_messages:
        print(f"vulkan validation: {message}", file=sys.stderr)
    print(f"ecs-engine: {len(result.validation_messages)} validation message(s)", file=sys.stderr)
    return 1
