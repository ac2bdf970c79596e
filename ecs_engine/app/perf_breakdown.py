"""Timings by name over the Perf window's rolling window: each system's CPU ms and each GPU
pass's ms, for the Perf window's lists and the console's summary line.

Only the frames that were timed (app/profiling.py: while the Perf window is open, or a trace or
a perf log is recorded) have a row; in a timed row a name it lacks counts 0 ms (a system its run
condition skipped, a pass the frame did not need), so a mean is the cost per frame and the
means add up to the frame's. Rows live in a NumPy ring that grows by doubling, as the monitor's.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import NamedTuple

import numpy as np

_START_ROWS = 256


class Timings(NamedTuple):
    """One frame's timings (app/profiling.py's Profiler.end_frame)."""

    systems: dict[str, float]  # CPU ms by system name, summed over its runs this frame
    threads: dict[str, str]  # the thread that ran each system (its last run this frame)
    gpu_passes: list[tuple[str, float]]  # (name, ms) of the frame whose GPU timestamps came back; [] if none


class NamedTime(NamedTuple):
    name: str
    mean: float  # ms per timed frame over the window
    max: float  # the window's largest


class Breakdown:
    """Rows of timed frames (time, ms by name), the last `window_s` seconds of them kept."""

    def __init__(self, window_s: float, max_rows: int) -> None:
        self.window_s = float(window_s)
        self.max_rows = int(max_rows)
        self.names: dict[str, int] = {}  # name -> column
        self._t = np.full(min(_START_ROWS, self.max_rows), math.nan)
        self._v = np.zeros((len(self._t), 0))
        self._next = 0
        self._rows = 0

    def add(self, t: float, values: Iterable[tuple[str, float]]) -> None:
        """One timed frame at clock time `t` (seconds, as the monitor's rows)."""
        if self._rows == len(self._t) and len(self._t) < self.max_rows and self._t[self._next] > t - self.window_s:
            self._grow()  # the oldest row is still inside the window
        i = self._next
        row = self._v[i]
        row[:] = 0.0
        names = self.names
        for name, ms in values:
            k = names.get(name)
            if k is None:
                k = names[name] = len(names)
                self._v = np.hstack((self._v, np.zeros((len(self._t), 1))))  # absent so far: 0 ms
                row = self._v[i]
            row[k] += ms
        self._t[i] = t
        self._rows = min(self._rows + 1, len(self._t))
        self._next = i + 1 if i + 1 < len(self._t) else 0

    def _grow(self) -> None:
        order = np.r_[self._next : len(self._t), 0 : self._next]  # oldest first
        size = min(2 * len(self._t), self.max_rows)
        t, v = np.full(size, math.nan), np.zeros((size, self._v.shape[1]))
        t[: len(order)], v[: len(order)] = self._t[order], self._v[order]
        self._t, self._v, self._next = t, v, len(order)

    def window(self, last_t: float) -> list[NamedTime]:
        """Each name's mean and max over the rows of the window ending at `last_t`, the largest
        mean first; [] when no timed frame is in the window."""
        inside = self._t > last_t - self.window_s  # NaN (rows never written): False
        if not inside.any() or not self.names:
            return []
        rows = self._v[inside]
        means, peaks = rows.mean(axis=0), rows.max(axis=0)
        found = [NamedTime(name, float(means[k]), float(peaks[k])) for name, k in self.names.items()]
        return sorted(found, key=lambda x: -x.mean)

    @property
    def capacity(self) -> int:
        return len(self._t)
