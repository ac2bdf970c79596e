"""A run without a GPU: an App with no RenderPlugin (MinimalPlugins) steps its schedule through
the one run loop (input scripts, recordings, Esc, Ctrl-C, the perf log and the summary lines as
any run) with a frame source that opens no device and a renderer that draws nothing. Vulkan is
never loaded, so a pure simulation runs where there is no GPU and no Vulkan loader at all.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from ..ecs.timestep import FixedTimestep
from ..errors import UsageError
from ..render.assets.meshes import MeshList
from ..render.draw.path import FrameStats
from .session import FrameTarget, Gpu, Session
from .settings import FIXED_DT, RunOptions, Settings


class NoGpu:
    """Stands where a run's Device does (its name for the run's first line, wait_idle)."""

    info = SimpleNamespace(name="CPU", driver_name="no", driver_info="GPU")
    ray_tracing = None

    def wait_idle(self) -> None:
        pass


class SimulationRenderer:
    """Stands where the renderer does: keeps the settings a run reports, draws nothing."""

    def __init__(self, start: Settings) -> None:
        self.mode, self.cpu_recorder, self.culling, self.fill = start.mode, start.recorder, start.culling, start.fill
        self.tone_map, self.exposure, self.light_culling = start.tone_map, start.exposure, start.light_culling
        self.transparency, self.lod = start.transparency, start.lod
        self.shadow_method, self.shadow_denoise = start.shadow_method, start.shadow_denoise
        self.replay = SimpleNamespace(enabled=start.frame_reuse)

    def ensure_output(self) -> None:
        pass

    def render(self, world: Any, **_: Any) -> FrameStats:
        return FrameStats(draws=0, instances=0, triangles=0, lights=0, gpu_ms=None)

    def destroy(self) -> None:
        pass


class SimulationSource:
    """Frames at a fixed 1/60 s, as headless runs step, until `frames` (or Esc, Window.close())."""

    window: Any = None
    input: Any = None
    instance: Any = None
    present_mode: str | None = None
    recreations = 0
    minimised_waits = 0

    def __init__(self) -> None:
        self.clock = FixedTimestep(FIXED_DT)
        self.max_frame_dt = FIXED_DT
        self.frames = 1
        self._close = False

    def open(self, options: RunOptions) -> Gpu:
        self.frames = options.frames or 1
        return Gpu(None, NoGpu(), None, MeshList())  # type: ignore[arg-type]

    def attach(self, session: Session) -> None:
        pass

    def running(self, frames_done: int) -> bool:
        if self._close:
            self._close = False
            self.frames = min(self.frames, frames_done)
        return frames_done < self.frames

    def request_close(self) -> None:
        self._close = True

    def abandon(self, session: Session, target: FrameTarget) -> None:
        pass

    def begin(self, session: Session, frames_done: int) -> FrameTarget:
        return FrameTarget(dt=FIXED_DT)

    def end(self, session: Session, target: FrameTarget) -> None:
        pass

    def describe(self, session: Session) -> str:
        return f"{session.scene}: simulation, no rendering, {self.frames} frames, {session.settings.threads} threads"

    def validation_messages(self) -> list[str]:
        return []

    def check_present(self, present: str) -> None:
        raise UsageError("a run without rendering has no swapchain, so no present mode")

    def set_present(self, present: str) -> None:
        self.check_present(present)

    def pixels(self) -> Any:
        return None

    def close(self) -> None:
        pass
