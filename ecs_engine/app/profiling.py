"""Per-system CPU times, per-job times and per-pass GPU times, frame by frame, switched on only
while someone looks at them.

The Profiler is the schedule's timer (each system's run, on the thread that ran it), the worker
pool's timer while a trace is recorded (each job), and turns on the frame ring's pass
timestamps (gpu/frames.py). Timing has a cost: a clock read either side of each system and a
call, and a timestamp per pass; on the 1-cube frame that is a few microseconds against a frame
of about a hundred (docs/performance.md, "Profiling"). So it is on only while the Perf window is
drawn (not collapsed, its tab shown), or for the whole run when a trace (`--trace`) or a perf
log (`--perf-json`) is recorded; otherwise the schedule and the pool test one attribute per stage
or batch and the renderer records no extra timestamps. A run that can never show the figures
(no editor, no trace, no log: the benchmarks) makes no Profiler at all.
"""

from __future__ import annotations

import threading
from threading import get_ident
from typing import Any

from ..gpu.frames import GpuFrame
from .perf_breakdown import Timings
from .trace import TraceRecorder


class Profiler:
    def __init__(self, trace: TraceRecorder | None = None, always: bool = False) -> None:
        """`always`: time every frame (a perf log); a trace times every frame too."""
        self.trace = trace
        self.always = always or trace is not None
        self.on = False
        self._systems: dict[str, int] = {}  # ns this frame by system
        self._threads: dict[str, int] = {}  # the ident of the thread that ran it
        self._thread_names: dict[int, str] = {}

    def begin_frame(self, session: Any, wanted: bool = False) -> None:
        """Time this frame if always, or if `wanted` (the Perf window was drawn last frame):
        attach to (or detach from) the session's schedule, pool and frame ring."""
        on = self.always or wanted
        self.on = on
        session.schedule.timer = self if on else None
        session.pool.timer = self if on and self.trace is not None else None
        session.renderer.frames.pass_timing = on

    def system(self, name: str, start_ns: int, end_ns: int) -> None:
        """The schedule's report of one system run (any thread): as little as it can do, as it
        runs once a system (names and units are resolved once a frame, in end_frame)."""
        systems = self._systems
        systems[name] = systems.get(name, 0) + (end_ns - start_ns)
        self._threads[name] = get_ident()
        if self.trace is not None:
            self.trace.span("system", name, start_ns, end_ns)

    def job(self, name: str, start_ns: int, end_ns: int) -> None:
        """The worker pool's report of one job (any thread)."""
        if self.trace is not None:
            self.trace.span("job", name, start_ns, end_ns)

    def end_frame(self, number: int, start_ns: int, end_ns: int, gpu: GpuFrame | None) -> Timings | None:
        """The frame's timings (None when it was not timed); the trace gets the frame."""
        if not self.on:
            return None
        names = self._thread_names
        if not set(self._threads.values()) <= names.keys():
            names.update((t.ident, t.name) for t in threading.enumerate() if t.ident is not None)
        systems = {name: ns * 1e-6 for name, ns in self._systems.items()}
        threads = {name: names.get(ident, str(ident)) for name, ident in self._threads.items()}
        timings = Timings(systems, threads, gpu.passes if gpu is not None else [])
        self._systems, self._threads = {}, {}
        if self.trace is not None:
            self.trace.frame(number, start_ns, end_ns, gpu)
        return timings
