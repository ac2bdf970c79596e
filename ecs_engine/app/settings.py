"""What a run is asked to do.

`RunOptions` is fixed for the whole run (frozen: a change is a new value, `dataclasses.replace`).
`Settings` are the few things that may change while it runs (the editor's controls); the
`Session` holds the current ones and is the one owner of each: the thread count lives in the
worker pool, the mode and recorder in the renderer's path, the present mode in the swapchain.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..jobs import default_threads
from ..render.renderer import default_recorder
from .scenes import SEED_SCENES

FIXED_DT = 1.0 / 60.0  # headless runs: one fixed step a frame, so a run is reproducible frame for frame
SIM_STEP = 1.0 / 120.0  # windowed runs: the fixed simulation step (ecs.FixedTimestep)
MAX_DT = 0.1  # a hitch (dragging the window, a breakpoint) must not fling the camera (per-frame stages)


@dataclass
class Settings:
    scene: str
    mode: str
    recorder: str  # native | python (the indirect mode records on the GPU: kept for switching back)
    threads: int  # worker pool size, counting the main thread
    culling: bool
    present: str | None  # fifo | mailbox | immediate; None: headless, no swapchain


@dataclass(frozen=True)
class RunOptions:
    """A run. `scene`, `mode`, `recorder`, `threads`, `culling` and `present` are where the
    run starts (see `settings()`); the editor may change them later."""

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
    threads: int | None = None  # None: all cores
    culling: bool = True
    chunk_rows: int | None = None  # rows per render job (None: about one per thread, frame_data.MIN_CHUNK_ROWS)
    recorder: str | None = None  # native | python (None: native when numba is there)
    entities: int = 10_000  # the scaling scene's entity count
    perf_json: str | None = None  # write every frame's perf samples here at the end
    editor: bool = False  # the ImGui editor and Perf window (headless: drawn into the image)
    scenes: tuple[str, ...] = SEED_SCENES  # the editor's scene switcher

    def settings(self) -> Settings:
        return Settings(
            scene=self.scene,
            mode=self.mode,
            recorder=self.recorder or default_recorder(),
            threads=self.threads or default_threads(),
            culling=self.culling,
            present=None if self.headless else self.present,
        )
