"""The numbers behind the performance overlay: frame rate, CPU/GPU frame times, CPU use, memory.

FPS comes from the wall-clock time between successive `frame()` calls, never from CPU time: a
frame that waits for vsync or the GPU is still a frame that took that long. The CPU, record, GPU
and wait times are measured by the renderer and handed in; GPU time may be missing (timestamps
of an earlier frame come back late or not at all) and is then left out of its statistics only.

Samples go into preallocated NumPy ring buffers holding the last `window_s` seconds, which grow
by doubling up to what `max_fps` needs, so a frame costs a few microseconds and a long run does
not grow memory. psutil is asked about 4 times a second, not every frame: a sample costs about
0.1 ms. With a log (`--perf-json`) every frame is also kept, in chunks, for the file
written at the end. Clock and sampler are injectable so tests run on simulated time.

The first `warmup_frames` frames (default 5) stay out of the rolling window and of the log's
summary: pipeline creation and JIT compiles land there (the first frame took 6.5 s on the
2-core development box), and one such frame would swamp the mean and p99 for the whole window.
The log still keeps their rows.

A frame may bring its timings by name (`timings`: each system's CPU ms and the thread that ran
it, each GPU pass's ms; app/profiling.py): they go into a window of their own
(perf_breakdown.py) for the Perf window's lists and the summary line, and into the log.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
import psutil

from .perf_breakdown import Breakdown, NamedTime, Timings
from .perf_log import COL, COLUMNS, METRICS, PerfLog, ProcessSample, Stats, check_writable, frame_rate, window_stats

__all__ = ["METRICS", "WARMUP_FRAMES", "PerfLog", "PerfMonitor", "ProcessSample", "PsutilSampler", "Stats"]
__all__ += ["Timings", "check_writable"]

_START_ROWS = 1024  # 5 s at 200 fps before the first doubling
_SLACK_ROWS = 16  # rounding at the window's edge never costs a sample
WARMUP_FRAMES = 5  # left out of the rolling statistics (and of a run's closing summary, report.py)
_NAN = math.nan
_T, _FRAME, _OVERHEAD = COL["t"], COL["frame_ms"], COL["overhead_ms"]


class Sampler(Protocol):
    """What PerfMonitor asks a few times a second; tests pass a fake with fixed values."""

    cores: int  # logical cores, to turn the process % into a per-core %

    def sample(self) -> ProcessSample: ...


class PsutilSampler:
    """psutil's view of the machine and of this process.

    `cpu_percent(interval=None)` reports the time since its previous call, and its first call
    returns a meaningless 0.0, so that first call is made here: the first sample covers the
    time since the sampler (and the monitor owning it) was made."""

    def __init__(self) -> None:
        self._process = psutil.Process()
        self.cores = psutil.cpu_count(logical=True) or 1
        psutil.cpu_percent(interval=None)
        self._process.cpu_percent(interval=None)

    def sample(self) -> ProcessSample:
        with self._process.oneshot():
            process = self._process.cpu_percent(interval=None)
            rss = self._process.memory_info().rss
        return ProcessSample(psutil.cpu_percent(interval=None), process, rss)


class PerfMonitor:
    """Per-frame samples over a rolling window, plus psutil samples a few times a second.

    Call `frame()` once per frame after submitting it. `log` keeps every frame for
    `write_json`: True in memory, or a path, checked for writability now and used by
    `write_json()` when it gets none. The first `warmup_frames` frames are logged but left out
    of the window."""

    def __init__(
        self,
        window_s: float = 5.0,
        sample_hz: float = 4.0,
        clock: Callable[[], float] = time.perf_counter,
        sampler: Sampler | None = None,
        log: bool | str | os.PathLike[str] = False,
        max_fps: float = 4000.0,
        warmup_frames: int = WARMUP_FRAMES,
    ) -> None:
        if not (window_s > 0 and sample_hz > 0 and max_fps > 0):
            raise ValueError(
                f"window_s, sample_hz and max_fps must be positive, got {window_s}, {sample_hz}, {max_fps}"
            )
        if warmup_frames < 0:
            raise ValueError(f"warmup_frames must be at least 0, got {warmup_frames}")
        self.warmup_frames = int(warmup_frames)
        self.window_s = float(window_s)
        self.sample_hz = float(sample_hz)
        self.log = None if log is False else PerfLog(None if log is True else log)
        self._clock = clock
        self._sampler = PsutilSampler() if sampler is None else sampler
        self.cores = max(1, int(self._sampler.cores))
        # beyond max_fps the ring keeps the last max_rows frames: a shorter window, same rates
        self.max_rows = math.ceil(self.window_s * max_fps) + _SLACK_ROWS
        self._ring = np.full((min(_START_ROWS, self.max_rows), len(COLUMNS)), _NAN)
        self._next = 0  # row written next; the oldest row once the ring is full
        self._rows = 0
        self._cache = (-1, 0)  # (frame_count, first window row in age order)
        self.frame_count = 0
        self.overhead_total_s = 0.0
        self.counters: dict[str, int] = {}
        # the world's resources that report on themselves (`perf_line()`: the sound's underruns),
        # asked only when a line or the Perf window shows them; the run loop names its world here
        self.gauges: Callable[[], Any] | None = None
        self.systems = Breakdown(self.window_s, self.max_rows)  # CPU ms by system (timed frames)
        self.gpu_passes = Breakdown(self.window_s, self.max_rows)  # GPU ms by pass
        self.system_threads: dict[str, str] = {}  # the thread that last ran each system
        self.sample: ProcessSample | None = None
        self._start = clock()
        self._last_t = _NAN
        self._next_sample_t = 0.0  # the first frame samples
        self._next_summary_t = 1.0

    def frame(
        self,
        cpu_ms: float,
        record_ms: float = 0.0,
        gpu_ms: float | None = None,
        wait_ms: float = 0.0,
        timings: Timings | None = None,
        **counters: int,
    ) -> None:
        """Record one frame. cpu_ms: frame start to submit; record_ms: command recording;
        gpu_ms: GPU time of the frame whose timestamps just came back, None if none did;
        wait_ms: time blocked on fences/acquire; timings: by system and GPU pass, None when the
        frame was not timed; counters: draws, visible, triangles, ..."""
        start = time.perf_counter()  # the monitor's own cost is real time, whatever the clock
        t = self._clock() - self._start
        row = (t, (t - self._last_t) * 1e3, cpu_ms, record_ms, _NAN if gpu_ms is None else gpu_ms, wait_ms, 0.0)
        self._last_t = t
        i = self._insert(t, row) if self.frame_count >= self.warmup_frames else None  # warm-up: no row
        self.frame_count += 1
        self.counters = counters
        if timings is not None:
            self.system_threads.update(timings.threads)
            if i is not None:
                self.systems.add(t, timings.systems.items())
                if timings.gpu_passes:
                    self.gpu_passes.add(t, timings.gpu_passes)
        log = self.log
        if log is not None:
            log.append(row, counters, timings)
        if t >= self._next_sample_t:
            self._take_sample(t)
        ms = (time.perf_counter() - start) * 1e3
        if i is not None:
            self._ring[i, _OVERHEAD] = ms
        self.overhead_total_s += ms * 1e-3
        if log is not None:
            log.set_overhead(ms)

    def _insert(self, t: float, row: tuple[float, ...]) -> int:
        """Put a row in the ring (grown if its oldest row is still in the window); its index."""
        ring = self._ring
        if self._rows < len(ring):
            self._rows += 1
        elif len(ring) < self.max_rows and ring[self._next, _T] > t - self.window_s:
            ring = self._grow()  # the oldest row is still inside the window
            self._rows += 1
        i = self._next
        ring[i] = row
        self._next = i + 1 if i + 1 < len(ring) else 0
        return i

    @property
    def warming_up(self) -> bool:
        """Still in the warm-up frames: the window is empty, every statistic NaN."""
        return self.frame_count < self.warmup_frames

    def _take_sample(self, t: float) -> None:
        self.sample = self._sampler.sample()
        if self.log is not None:
            self.log.add_sample(t, self.sample)
        period = 1.0 / self.sample_hz
        self._next_sample_t += period
        if self._next_sample_t <= t:  # after a stall: carry on at the rate, no burst of samples
            self._next_sample_t = t + period

    def _grow(self) -> np.ndarray:
        """Double the ring (up to max_rows), rows in age order; happens a few times a run."""
        grown = np.full((min(2 * len(self._ring), self.max_rows), len(COLUMNS)), _NAN)
        grown[: self._rows] = np.concatenate((self._ring[self._next :], self._ring[: self._next]))
        self._ring = grown
        self._next = self._rows
        return grown

    @property
    def capacity(self) -> int:
        """Rows the ring holds now (grows by doubling up to max_rows)."""
        return len(self._ring)

    def _window(self, column: int) -> np.ndarray:
        """One column over the window, oldest first (a copy)."""
        ring, n = self._ring, self._rows
        cap = len(ring)
        base = self._next if n == cap else 0  # ring row of the oldest frame
        if self._cache[0] != self.frame_count:  # the overlay asks for several metrics a frame
            times = np.concatenate((ring[base:n, _T], ring[:base, _T]))
            first = int(np.searchsorted(times, self._last_t - self.window_s, side="right")) if n else 0
            self._cache = (self.frame_count, first)
        start = base + self._cache[1]
        if start >= cap:
            return ring[start - cap : base, column].copy()
        if n < cap:
            return ring[start:n, column].copy()
        return np.concatenate((ring[start:, column], ring[:base, column]))

    def series(self, name: str) -> np.ndarray:
        """float64 values of a metric over the window, oldest first, for the plots (NaN where
        unknown: the first frame's interval, missing GPU times)."""
        return self._window(self._column(name))

    def times(self) -> np.ndarray:
        """Seconds since the monitor was made of the frames in the window, aligned with series()."""
        return self._window(_T)

    def stats(self, name: str) -> Stats:
        """min, mean, p99 of a metric over the window, NaNs (missing GPU times) left out."""
        return window_stats(self.series(name))

    @staticmethod
    def _column(name: str) -> int:
        if name not in METRICS:
            raise ValueError(f"unknown metric {name!r}; known: {', '.join(METRICS)}")
        return COL[name]

    @property
    def fps(self) -> float:
        """Frames per second over the window, from wall-clock intervals; NaN before two frames."""
        return frame_rate(self._window(_FRAME))

    @property
    def overhead_ms(self) -> float:
        """Mean time per frame spent inside frame() (psutil sampling included) over the window."""
        return float(self._window(_OVERHEAD).mean()) if self._rows else _NAN

    @property
    def cpu_system_percent(self) -> float:
        return self.sample.cpu_system_percent if self.sample else _NAN

    @property
    def cpu_process_percent(self) -> float:
        """100 per fully busy core: above 100 when several threads work."""
        return self.sample.cpu_process_percent if self.sample else _NAN

    @property
    def cpu_process_percent_per_core(self) -> float:
        """The process % over all logical cores (0-100), comparable with the system %."""
        return self.cpu_process_percent / self.cores

    @property
    def rss_bytes(self) -> int:
        """Resident memory at the latest sample; 0 before the first frame."""
        return int(self.sample.rss_bytes) if self.sample else 0

    def summary_due(self) -> bool:
        """True once per second of clock time: a headless run prints summary_line() then."""
        now = self._clock() - self._start
        if now < self._next_summary_t:
            return False
        self._next_summary_t += 1.0
        if self._next_summary_t <= now:
            self._next_summary_t = now + 1.0
        return True

    def summary_line(self) -> str:
        """One line over the window, e.g. `fps 1234 | cpu 0.41 ms (p99 0.62) | record 0.08 |
        gpu 0.37 ms | sys 6% proc 101% (6.3%/core) | rss 210 MiB | 100 drawn in 2 draws`, and
        while frames are timed the three slowest systems and GPU passes (`| systems TransformSystem
        0.031, ... ms | gpu passes forward 0.290, ... ms`)."""
        cpu, record, gpu = self.stats("cpu_ms"), self.stats("record_ms"), self.stats("gpu_ms")
        if self.warming_up:
            parts = [f"warm-up frame {self.frame_count} of {self.warmup_frames} (left out of the figures)"]
        else:
            parts = [
                f"fps {_fmt(self.fps, '.0f')}",
                f"cpu {_fmt(cpu.mean, '.2f')} ms (p99 {_fmt(cpu.p99, '.2f')})",
                f"record {_fmt(record.mean, '.2f')}",
                f"gpu {_fmt(gpu.mean, '.2f')} ms" if not math.isnan(gpu.mean) else "gpu n/a",
            ]
        if self.sample is None:
            parts.append("sys n/a")
        else:
            parts.append(
                f"sys {self.cpu_system_percent:.0f}% proc {self.cpu_process_percent:.0f}% "
                f"({self.cpu_process_percent_per_core:.1f}%/core)"
            )
            parts.append(f"rss {self.rss_bytes / 2**20:.0f} MiB")
        counters = dict(self.counters)
        if "visible" in counters and "draws" in counters:
            parts.append(f"{counters.pop('visible')} drawn in {counters.pop('draws')} draws")
        parts.extend(f"{name} {value}" for name, value in counters.items())
        for label, found in (("systems", self.system_times()), ("gpu passes", self.gpu_pass_times())):
            if found:  # the slowest three: the line is read at a glance
                parts.append(f"{label} " + ", ".join(f"{x.name} {x.mean:.3f}" for x in found[:3]) + " ms")
        parts.extend(self.gauge_lines())
        return " | ".join(parts)

    def gauge_lines(self) -> list[str]:
        """What the world's resources say of themselves (a resource with `perf_line()`)."""
        resources = self.gauges() if self.gauges is not None else {}
        return [r.perf_line() for r in list(resources.values()) if callable(getattr(r, "perf_line", None))]

    def system_times(self) -> list[NamedTime]:
        """Each system's CPU ms per frame over the window (timed frames only), slowest first."""
        return self.systems.window(self._last_t)

    def gpu_pass_times(self) -> list[NamedTime]:
        """Each GPU pass's ms per frame over the window (timed frames only), slowest first."""
        return self.gpu_passes.window(self._last_t)

    def write_json(self, path: str | os.PathLike[str] | None = None, meta: dict[str, Any] | None = None) -> None:
        """Write every frame of the run (`--perf-json`); needs log=True or a log path. A path
        that cannot be written raises UsageError naming it."""
        if self.log is None:
            raise ValueError("write_json needs a PerfMonitor made with log=True or log=PATH")
        target = path if path is not None else self.log.path
        if target is None:
            raise ValueError("write_json needs a path: the monitor was made with log=True, not a path")
        self.log.write_json(target, {"logical_cores": self.cores, **(meta or {})}, self.cores, self.warmup_frames)


def _fmt(x: float, spec: str) -> str:
    return "n/a" if math.isnan(x) else format(x, spec)
