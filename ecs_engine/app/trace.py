"""`--trace out.json`: a Chrome trace-event file (open it in https://ui.perfetto.dev or
chrome://tracing) of the run's frames, its systems and the worker pool's jobs on the threads
that ran them, and the GPU passes on a track of their own.

Memory stays bounded: the recorder keeps the last `max_frames` frames (a ring, 3,000 by
default: about 50 s at 60 fps) and drops older ones whole; the file then says how many came
before (`otherData.frames_left_out`, and an instant event at the start of the first kept frame).
The file is written at the end of the run, also when Ctrl-C stops it, like `--perf-json`.

GPU times come from timestamps on the device's clock, which shares no zero with the CPU's
(perf_counter). They are placed on the CPU's timeline by one offset for the whole file: every
frame's GPU work started after its submit and ended before its fence was seen signalled, so the
offset lies between the largest (submit - GPU start) and the smallest (fence seen - GPU end)
over the frames kept; the earliest placement (the largest lower bound) is used, and the width of
that interval is written as `otherData.gpu_clock.uncertainty_us`: the GPU slices may sit up to
that much later. A GPU frame that would start before the previous one ended (the top-of-pipe
stamp) is shown from that end, so the track's slices do not overlap. Device clocks with fewer
than 64 valid bits wrap: a long trace on such a device may place frames wrongly.
"""

from __future__ import annotations

import bisect
import os
import threading
from collections import deque
from pathlib import Path
from time import perf_counter_ns
from typing import Any

from ..gpu.frames import GpuFrame
from .output_files import write_json_file

DEFAULT_FRAMES = 3000
CPU_PID, GPU_PID = 1, 2
GPU_TID = 1

Span = tuple[str, str, int, int, int]  # category, name, thread ident, start ns, end ns


class TraceRecorder:
    """Spans by thread (systems, jobs), frames, and the GPU frames that came back, for the last
    `max_frames` frames. `span` may be called from any thread (list.append holds the GIL)."""

    def __init__(self, path: str | os.PathLike[str], max_frames: int = DEFAULT_FRAMES) -> None:
        if max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {max_frames}")
        self.path = Path(path)
        self.max_frames = int(max_frames)
        self._frames: deque[tuple[list[Span], GpuFrame | None]] = deque(maxlen=self.max_frames)
        self._current: list[Span] = []
        self._threads: dict[int, str] = {}
        self.frames_seen = 0
        self.origin_ns = perf_counter_ns()

    def span(self, category: str, name: str, start_ns: int, end_ns: int) -> None:
        ident = threading.get_ident()
        if ident not in self._threads:
            self._threads[ident] = threading.current_thread().name
        self._current.append((category, name, ident, start_ns, end_ns))

    def frame(self, number: int, start_ns: int, end_ns: int, gpu: GpuFrame | None) -> None:
        """Frame `number` ran from start to end (perf_counter_ns); `gpu`: the GPU times that came
        back during it (of an earlier frame)."""
        self.span("frame", f"frame {number}", start_ns, end_ns)
        spans, self._current = self._current, []
        self._frames.append((spans, gpu))
        self.frames_seen += 1

    @property
    def frames_left_out(self) -> int:
        return self.frames_seen - len(self._frames)

    def document(self, meta: dict[str, Any] | None = None) -> dict[str, Any]:
        """The trace as a JSON-ready dict: events sorted by time (an enclosing slice first)."""

        def us(ns: int) -> float:  # the file's time unit, from the recorder's start
            return (ns - self.origin_ns) / 1e3

        tids = self._tids()
        events: list[dict[str, Any]] = []
        frames: list[tuple[int, int, str]] = []  # (start, end, name) of the frames kept, for the GPU's
        for spans, _ in self._frames:
            for category, name, ident, start, end in spans:
                event = {"name": name, "cat": category, "ph": "X", "ts": us(start), "dur": (end - start) / 1e3}
                events.append({**event, "pid": CPU_PID, "tid": tids[ident]})
                if category == "frame":
                    frames.append((start, end, name))
        gpus = [gpu for _, gpu in self._frames if gpu is not None]
        clock = gpu_clock(gpus)
        if clock is not None:
            events += self._gpu_events(gpus, clock[0], frames, us)
        left_out = self.frames_left_out
        if left_out and events:
            first = min(e["ts"] for e in events)
            note = f"{left_out} earlier frames left out (the trace keeps the last {self.max_frames})"
            events.append({"name": note, "ph": "i", "s": "g", "ts": first, "pid": CPU_PID, "tid": 1})
        events.sort(key=lambda e: (e["ts"], -e.get("dur", 0.0)))
        other: dict[str, Any] = dict(meta or {})
        other.update(
            frames_recorded=self.frames_seen,
            frames_in_file=len(self._frames),
            frames_left_out=left_out,
            kept=f"the last {self.max_frames} frames",
        )
        if clock is not None:
            other["gpu_clock"] = {"offset_ns": clock[0], "uncertainty_us": clock[1] / 1e3}
        return {"traceEvents": self._names(tids, bool(gpus)) + events, "displayTimeUnit": "ms", "otherData": other}

    def _tids(self) -> dict[int, int]:
        """Small thread numbers for the file: the main thread 1, the others in order of appearance."""
        main = threading.main_thread().ident
        order = sorted(self._threads, key=lambda ident: ident != main)
        return {ident: k + 1 for k, ident in enumerate(order)}

    def _names(self, tids: dict[int, int], gpu: bool) -> list[dict[str, Any]]:
        meta = [{"name": "process_name", "ph": "M", "pid": CPU_PID, "args": {"name": "CPU"}}]
        for ident, tid in tids.items():
            name = self._threads[ident]
            meta.append({"name": "thread_name", "ph": "M", "pid": CPU_PID, "tid": tid, "args": {"name": name}})
            meta.append(
                {"name": "thread_sort_index", "ph": "M", "pid": CPU_PID, "tid": tid, "args": {"sort_index": tid}}
            )
        if gpu:
            meta.append({"name": "process_name", "ph": "M", "pid": GPU_PID, "args": {"name": "GPU"}})
            meta.append({"name": "thread_name", "ph": "M", "pid": GPU_PID, "tid": GPU_TID, "args": {"name": "queue"}})
        return meta

    def _gpu_events(
        self, gpus: list[GpuFrame], offset: int, frames: list[tuple[int, int, str]], us: Any
    ) -> list[dict[str, Any]]:
        """Each GPU frame as a slice named for the CPU frame that submitted it, its passes inside."""
        events: list[dict[str, Any]] = []
        starts = [f[0] for f in frames]
        previous_end = None
        for gpu in sorted(gpus, key=lambda g: g.start_ns):
            start = gpu.start_ns + offset
            if previous_end is not None and start < previous_end:
                start = previous_end
            k = bisect.bisect_right(starts, gpu.submitted_ns) - 1
            submitted_by = frames[k][2] if k >= 0 and gpu.submitted_ns <= frames[k][1] else "an earlier frame"
            base = {"ph": "X", "pid": GPU_PID, "tid": GPU_TID}
            args = {"submitted by": submitted_by}
            events.append(
                {
                    "name": f"GPU: {submitted_by}",
                    "cat": "gpu",
                    "ts": us(start),
                    "dur": gpu.ms * 1e3,
                    **base,
                    "args": args,
                }
            )
            t = start
            for name, ms in gpu.passes:
                events.append({"name": name, "cat": "gpu pass", "ts": us(t), "dur": ms * 1e3, **base})
                t += round(ms * 1e6)
            previous_end = start + round(gpu.ms * 1e6)
        return events

    def write(self, meta: dict[str, Any] | None = None) -> None:
        """Write the file: to a temporary file beside it, renamed over the target (a reader or
        a crash never sees half a file). An OSError is a UsageError naming the path."""
        write_json_file(self.path, self.document(meta), f"--trace {self.path}", "the trace")


def gpu_clock(gpus: list[GpuFrame]) -> tuple[int, int] | None:
    """(offset, uncertainty) in ns: GPU clock + offset = perf_counter_ns (see the module)."""
    if not gpus:
        return None
    low = max(g.submitted_ns - g.start_ns for g in gpus)
    high = min(g.done_ns - (g.start_ns + round(g.ms * 1e6)) for g in gpus)
    return low, max(0, high - low)
