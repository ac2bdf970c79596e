"""The per-frame columns of the performance figures, their statistics, and the log of every
frame that `--perf-json` writes at the end of a run (PerfLog).

Besides the fixed columns, a frame may carry timings by name (app/profiling.py): each system's
CPU ms and each GPU pass's ms, for the frames in which they were measured (the Perf window was
open, or a trace or log was asked for). The file gives them per frame (`systems_ms`,
`gpu_passes_ms`) and summarised over the timed frames after the warm-up (`systems`,
`gpu_passes`: min, mean and p99 per name, a name absent from a timed frame counting 0 ms there:
a system whose run condition skipped it, a pass the frame did not need).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..errors import UsageError
from .output_files import probe_write, write_json_file

if TYPE_CHECKING:
    from .perf_breakdown import Timings

SCHEMA_VERSION = 1

# Columns of the ring and of the log, one row per frame; METRICS are what stats()/series() know.
COLUMNS = ("t", "frame_ms", "cpu_ms", "record_ms", "gpu_ms", "wait_ms", "overhead_ms")
METRICS = COLUMNS[1:]
COL = {name: k for k, name in enumerate(COLUMNS)}
TIMING_GROUPS = ("systems", "gpu_passes")  # timings by name: the file's keys
_FRAME, _OVERHEAD = COL["frame_ms"], COL["overhead_ms"]
_NAN = math.nan


class ProcessSample(NamedTuple):
    cpu_system_percent: float  # whole machine, 0-100
    cpu_process_percent: float  # this process, 100 per busy core (can exceed 100)
    rss_bytes: int


class Stats(NamedTuple):
    """Window statistics of one metric; all NaN when it has no value in the window."""

    min: float
    mean: float
    p99: float


def check_writable(path: str | os.PathLike[str], what: str = "the performance log") -> Path:
    """The path as a Path if a file can be written there, else UsageError in one line.

    Called when the run starts, so a long run does not end by losing its data: a scratch file
    is created (and removed) next to the target, as the final write will do."""
    if not str(path):
        raise UsageError(f"the path for {what} is empty")
    target = Path(path)
    if target.is_dir():
        raise UsageError(f"{target}: is a directory, not a file to write {what} to")
    if not target.parent.is_dir():
        raise UsageError(f"{target}: cannot write {what} there: folder {target.parent} does not exist")
    probe_write(target, str(target), what)
    return target


def window_stats(values: np.ndarray) -> Stats:
    """min, mean and 99th percentile ignoring NaNs. The percentile is np.percentile's default
    (linear interpolation) from one partition: np.percentile costs ~75 us even on 300 values,
    too much for an overlay that asks every frame."""
    values = values[~np.isnan(values)]  # a copy, partitioned in place below
    n = values.size
    if n == 0:
        return Stats(_NAN, _NAN, _NAN)
    low, mean = float(values.min()), float(values.mean())
    pos = 0.99 * (n - 1)
    k = int(pos)
    values.partition(k)
    p99 = float(values[k])
    if k + 1 < n:  # everything after k is >= values[k]; the next order statistic is their min
        p99 += (float(values[k + 1 :].min()) - p99) * (pos - k)
    return Stats(low, mean, p99)


def frame_rate(frame_ms: np.ndarray) -> float:
    """Frames per second from wall intervals: intervals counted / their total time."""
    intervals = frame_ms[~np.isnan(frame_ms)]
    total = float(intervals.sum())
    return intervals.size * 1e3 / total if intervals.size and total > 0 else _NAN


def json_number(x: float) -> float | None:
    return None if math.isnan(x) else x


class PerfLog:
    """Every frame of the run (not just the window), for `--perf-json`.

    Rows go into (CHUNK, columns) float64 blocks, a new block every CHUNK frames: ~60 bytes a
    frame and no per-frame allocation. Counters get a NaN-filled column per block the first
    time a block sees their name, and timings by name (group, name) one too."""

    CHUNK = 8192

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        self.path = None if path is None else check_writable(path)
        self._blocks: list[np.ndarray] = []
        self._block_counters: list[dict[str, np.ndarray]] = []
        self._rows = np.empty((0, len(COLUMNS)))
        self._counters: dict[str, np.ndarray] = {}
        self._block_timings: list[dict[tuple[str, str], np.ndarray]] = []
        self._timings: dict[tuple[str, str], np.ndarray] = {}
        self._block_timed: list[np.ndarray] = []  # per block: (CHUNK, groups), whether each frame was timed
        self._timed = np.zeros((0, len(TIMING_GROUPS)), dtype=bool)
        self._j = self.CHUNK  # the first append opens a block
        self.samples: list[tuple[float, ProcessSample]] = []

    def __len__(self) -> int:
        return (len(self._blocks) - 1) * self.CHUNK + self._j if self._blocks else 0

    def append(self, row: tuple[float, ...], counters: dict[str, int], timings: Timings | None = None) -> None:
        j = self._j
        if j == self.CHUNK:
            self._rows = np.empty((self.CHUNK, len(COLUMNS)))
            self._counters, self._timings = {}, {}
            self._timed = np.zeros((self.CHUNK, len(TIMING_GROUPS)), dtype=bool)
            self._blocks.append(self._rows)
            self._block_counters.append(self._counters)
            self._block_timings.append(self._timings)
            self._block_timed.append(self._timed)
            j = 0
        self._rows[j] = row
        for name, value in counters.items():
            column = self._counters.get(name)
            if column is None:
                column = self._counters[name] = np.full(self.CHUNK, _NAN)
            column[j] = value
        if timings is not None:
            self._add_timings(j, timings)
        self._j = j + 1

    def _add_timings(self, j: int, timings: Timings) -> None:
        for g, values in enumerate((timings.systems.items(), timings.gpu_passes)):
            if g and not timings.gpu_passes:
                continue  # no GPU timestamps came back this frame: not a timed frame for passes
            self._timed[j, g] = True
            group = TIMING_GROUPS[g]
            for name, ms in values:
                column = self._timings.get((group, name))
                if column is None:
                    column = self._timings[(group, name)] = np.full(self.CHUNK, _NAN)
                column[j] = ms if math.isnan(column[j]) else column[j] + ms

    def set_overhead(self, ms: float) -> None:
        """The monitor's own cost for the last frame, known only once it is done."""
        self._rows[self._j - 1, _OVERHEAD] = ms

    def add_sample(self, t: float, sample: ProcessSample) -> None:
        self.samples.append((t, sample))

    def columns(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """All rows (frames, columns) and the counters (NaN where a frame had none)."""
        n = len(self)
        if n == 0:
            return np.empty((0, len(COLUMNS))), {}
        rows = np.concatenate(self._blocks)[:n]
        names = dict.fromkeys(name for block in self._block_counters for name in block)
        counters = {
            name: np.concatenate([block.get(name, np.full(self.CHUNK, _NAN)) for block in self._block_counters])[:n]
            for name in names
        }
        return rows, counters

    def timings(self) -> dict[str, tuple[np.ndarray, dict[str, np.ndarray]]]:
        """Per group ("systems", "gpu_passes"): which frames were timed, and each name's ms (NaN
        where a frame was not timed, 0 where it was and the name was absent)."""
        n = len(self)
        found: dict[str, tuple[np.ndarray, dict[str, np.ndarray]]] = {}
        if n == 0:
            return found
        timed = np.concatenate(self._block_timed)[:n]
        keys = dict.fromkeys(key for block in self._block_timings for key in block)
        for g, group in enumerate(TIMING_GROUPS):
            if not timed[:, g].any():
                continue
            names: dict[str, np.ndarray] = {}
            for key in (k for k in keys if k[0] == group):
                blank = np.full(self.CHUNK, _NAN)
                column = np.concatenate([block.get(key, blank) for block in self._block_timings])[:n]
                names[key[1]] = np.where(timed[:, g] & np.isnan(column), 0.0, column)
            found[group] = (timed[:, g], names)
        return found

    def _timing_fields(self, frames: list[dict[str, Any]], warmup: int) -> dict[str, Any]:
        """Per frame `systems_ms` and `gpu_passes_ms` where it was timed; the summary of each
        name over the timed frames after the warm-up (slowest mean first)."""
        summaries: dict[str, Any] = {}
        for group, (timed, names) in self.timings().items():
            key = f"{group}_ms"
            for i in np.flatnonzero(timed).tolist():
                frames[i][key] = {name: float(column[i]) for name, column in names.items()}
            steady = timed.copy()
            steady[:warmup] = False
            stats = {name: window_stats(column[steady]) for name, column in names.items()}
            order = sorted(stats, key=lambda name: -np.nan_to_num(stats[name].mean, nan=-1.0))
            summaries[group] = {name: {k: json_number(v) for k, v in stats[name]._asdict().items()} for name in order}
        return summaries

    def to_dict(self, meta: dict[str, Any], cores: int, warmup: int = 0) -> dict[str, Any]:
        """The JSON document (schema_version 1); NaN becomes null. The summary and fps leave out
        the first `warmup` frames (when there are more frames than that)."""
        rows, counters = self.columns()
        steady = rows[warmup:] if len(rows) > warmup else rows
        fields = COLUMNS[:_OVERHEAD]  # the per-frame cost is only summarised
        columns = [[json_number(x) for x in rows[:, k].tolist()] for k in range(len(fields))]
        frames = [dict(zip(fields, values, strict=True)) for values in zip(*columns, strict=True)]
        for name, column in counters.items():
            for frame, value in zip(frames, column.tolist(), strict=True):
                if not math.isnan(value):
                    frame[name] = int(value)
        psutil_rows = [
            {
                "t": t,
                "cpu_system_percent": s.cpu_system_percent,
                "cpu_process_percent": s.cpu_process_percent,
                "cpu_process_percent_per_core": s.cpu_process_percent / cores,
                "rss_bytes": int(s.rss_bytes),
            }
            for t, s in self.samples
        ]
        summary = {
            name: {k: json_number(v) for k, v in window_stats(steady[:, COL[name]])._asdict().items()}
            for name in METRICS
        }
        return {
            "schema_version": SCHEMA_VERSION,
            "meta": meta,
            "frames": frames,
            "psutil": psutil_rows,
            "warmup_frames": len(rows) - len(steady),
            "summary": summary,
            "fps": json_number(frame_rate(steady[:, _FRAME])),
            **self._timing_fields(frames, len(rows) - len(steady)),
        }

    def write_json(self, path: str | os.PathLike[str], meta: dict[str, Any], cores: int, warmup: int = 0) -> None:
        """Write to a temporary file in the same folder, then rename over the target: a reader
        (or a crash) never sees half a file."""
        target = Path(path)
        write_json_file(target, self.to_dict(meta, cores, warmup), str(target), "the performance log")
