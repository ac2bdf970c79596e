"""The headless frame source: an offscreen image, no window, surface or swapchain (no display
needed), and a fixed time step, so a run is reproducible frame for frame.

A source opens its own Vulkan instance and device, or draws on one it is given (`device=`, or
every source made inside `sharing(...)`): some drivers refuse new instances after about 30 in one
process (NVIDIA's did, on the GPU host), which a test suite of many runs reaches.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from ..ecs.timestep import FixedTimestep
from ..errors import UsageError
from ..gpu.device import Device
from ..gpu.instance import Instance
from ..gpu.offscreen import OffscreenTarget
from ..render.assets.mesh_registry import MeshRegistry
from ..render.config import check_samples
from .report import recorder_words
from .session import FrameTarget, Gpu, Session
from .settings import FIXED_DT, RunOptions

_shared: Callable[[], Device] | None = None


@contextmanager
def sharing(device: Callable[[], Device]) -> Iterator[None]:
    """Sources made inside the block draw on `device()` (called when one opens; the caller owns
    the device and destroys it) instead of opening an instance and device each."""
    global _shared
    before, _shared = _shared, device
    try:
        yield
    finally:
        _shared = before


class OffscreenSource:
    window: Any = None
    input: Any = None
    present_mode: str | None = None  # no swapchain
    recreations = 0
    minimised_waits = 0

    def __init__(self, device: Device | None = None) -> None:
        self._borrowed: Callable[[], Device] | None = (lambda: device) if device is not None else _shared
        self.clock = FixedTimestep(FIXED_DT)  # one step a frame
        self.max_frame_dt = FIXED_DT
        self.frames = 1
        self.readback_last = False
        self._close = False  # Esc: the run ends after this frame
        self._gpu: Gpu | None = None
        self.instance: Instance | None = None  # its validation messages outlive the run
        self._first_message = 0  # on a borrowed device: the instance's messages before this run
        self._opened: list[Any] = []  # what to destroy, in the order made

    def open(self, options: RunOptions) -> Gpu:
        self.frames = options.frames or 1
        self.readback_last = options.screenshot is not None
        self.width, self.height = options.width, options.height
        if self._borrowed is not None:
            device = self._borrowed()
            instance = self.instance = device.instance
            self._first_message = len(instance.messages)
        else:
            instance = self.instance = self._keep(Instance(validate=options.validate))
            device = self._keep(Device(instance))
        check_samples(device, options.msaa)
        target = self._keep(OffscreenTarget(device, options.width, options.height, options.msaa))
        meshes = self._keep(MeshRegistry(device))
        self._gpu = Gpu(instance, device, target, meshes)
        return self._gpu

    def _keep(self, obj: Any) -> Any:
        self._opened.append(obj)
        return obj

    def attach(self, session: Session) -> None:
        pass

    def running(self, frames_done: int) -> bool:
        if self._close:  # one more frame, read back, when the run has a --screenshot to write
            self._close = False
            self.frames = min(self.frames, frames_done + (1 if self.readback_last else 0))
        return frames_done < self.frames

    def request_close(self) -> None:
        self._close = True

    def abandon(self, session: Session, target: FrameTarget) -> None:
        pass  # nothing was acquired

    def begin(self, session: Session, frames_done: int) -> FrameTarget:
        return FrameTarget(dt=FIXED_DT, readback=self.readback_last and frames_done == self.frames - 1)

    def end(self, session: Session, target: FrameTarget) -> None:
        pass

    def describe(self, session: Session) -> str:
        s = session.settings
        return (
            f"{s.scene}: headless {self.width}x{self.height}, {self.frames} frames, mode {s.mode}, "
            f"{recorder_words(s.mode, s.recorder)}, {s.threads} threads"
        )

    def validation_messages(self) -> list[str]:
        """What the validation layers said during this run (on a shared instance: only since
        this source opened)."""
        return [] if self.instance is None else self.instance.messages[self._first_message :]

    def check_present(self, present: str) -> None:
        raise UsageError("a headless run has no swapchain, so no present mode")

    def set_present(self, present: str) -> None:
        self.check_present(present)

    def pixels(self) -> Any:
        """The image of the last frame rendered with readback (the screenshot's frame)."""
        assert self._gpu is not None
        return self._gpu.target.pixels()

    def close(self) -> None:
        while self._opened:
            self._opened.pop().destroy()
