"""What a run leaves behind: per-frame figures (`RunResult`), the summary lines, the screenshot
and the validation report."""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import UsageError
from ..render.frame.renderer import PATHS
from .perf import WARMUP_FRAMES  # left out of the closing summary too
from .settings import RunOptions


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
    profiler: Any = None  # the run's profiling.Profiler (None: nothing can show the timings)
    editor: Any = None  # the run's editor_session.EditorSession, while it runs
    settings: Any = None  # the session's Settings when the run ended
    recreations: int = 0  # swapchain recreations (windowed)
    minimised_waits: int = 0  # loop turns spent waiting while minimised (windowed)
    replayed: list[bool] = field(default_factory=list)  # per frame: its slot's recording submitted again

    @property
    def fps(self) -> float:
        return self.frames / self.wall_s if self.wall_s > 0 else 0.0

    def add_frame(
        self,
        stats: Any,
        cpu_ms: float,
        end: float,
        waited_ms: float = 0.0,
        ui_ms: float | None = None,
        timings: Any = None,
    ) -> None:
        """One frame's figures, into the lists and the perf monitor. `waited_ms`: time blocked
        outside the renderer (the swapchain), on top of `stats.wait_ms`; `timings`: by system
        and GPU pass (perf_breakdown.Timings), None when the frame was not timed."""
        self.cpu_ms.append(cpu_ms)
        self.frame_end.append(end)
        self.record_ms.append(stats.record_ms)
        self.replayed.append(stats.replayed)
        if stats.gpu_ms is not None:
            self.gpu_ms.append(stats.gpu_ms)
        if ui_ms is not None:
            self.ui_ms.append(ui_ms)
        self.last_stats = stats
        self.perf.frame(
            cpu_ms,
            stats.record_ms,
            stats.gpu_ms,
            stats.wait_ms + waited_ms,
            timings,
            draws=stats.draws,
            visible=stats.instances,
        )

    def write_perf_json(self, options: RunOptions, say: Callable[[str], None]) -> None:
        """`--perf-json`: every frame's samples, with what the run was."""
        if options.perf_json:
            self.perf.write_json(meta=self.meta(options))
            say(f"wrote {options.perf_json}")

    def write_trace(self, options: RunOptions, say: Callable[[str], None]) -> None:
        """`--trace`: the frames the trace kept (app/trace.py), with what the run was."""
        trace = self.profiler.trace if self.profiler is not None else None
        if options.trace and trace is not None:
            trace.write(meta=self.meta(options))
            say(f"wrote {options.trace}")

    def meta(self, options: RunOptions) -> dict[str, Any]:
        """What a --perf-json file says about its run (the settings it ended with)."""
        s = self.settings or options.settings()
        return {
            "scene": s.scene,
            "mode": s.mode,
            "threads": s.threads,
            "culling": s.culling,
            "width": options.width,
            "height": options.height,
            "headless": options.headless,
            "device": self.device,
            "frames": self.frames,
            "wall_s": self.wall_s,
            "editor": options.editor,
        }

    def record_ms_mean(self, warmup: int = 0) -> float:
        values = self.record_ms[warmup:] or self.record_ms
        return float(np.mean(values)) if values else 0.0

    def fps_after(self, warmup: int) -> float:
        """Frames per second of wall clock over the frames after the first `warmup`."""
        if warmup < 1 or len(self.frame_end) <= warmup:
            return self.fps
        return (len(self.frame_end) - warmup) / (self.frame_end[-1] - self.frame_end[warmup - 1])


def describe_device(device: Any) -> str:
    return f"{device.info.name} ({device.info.driver_name} {device.info.driver_info})".strip()


def recorder_words(mode: str, recorder: str) -> str:
    """How a run's draws are recorded: by the recorder setting, or on the GPU."""
    return f"{recorder} recorder" if PATHS[mode].uses_recorder else "commands written on the GPU"


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
    return (
        f"{label}: {frames / wall_s if wall_s > 0 else 0:.0f} fps (wall clock), cpu {cpu.mean():.3f} ms "
        f"(p99 {np.percentile(cpu, 99):.3f}, record {record.mean():.3f}), {gpu_text}; "
        f"{stats.instances} of {stats.candidates} entities "
        f"drawn in {stats.draws} draws, {stats.triangles} triangles, {stats.lights} lights"
    )


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
