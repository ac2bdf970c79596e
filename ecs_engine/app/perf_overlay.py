"""The Perf window: the PerfMonitor's numbers as ImGui text and implot rolling plots.

The numbers and plot lines are refreshed a few times a second, not every frame: reading the
window's statistics costs ~0.3 ms at 1,000 FPS (percentiles over 5,000 rows), more than the
whole overlay may cost.

FPS is wall clock; CPU frame, record and GPU ms (timestamps) come with min, mean and 99th
percentile over the window; CPU system and process % (raw and per core) and resident memory
come from psutil samples taken about 4 times a second; the overlay's own cost is shown too.
The first frames (the monitor's warm-up: pipelines and JIT compiles) are left out of all of it;
until the window has two frames the FPS line says so instead of showing NaN.

Below them, each system's CPU ms per frame (and the thread that last ran it) and each GPU pass's
ms, slowest first, as means over the same window; they are measured only while this window is
drawn (app/profiling.py), so the first frame after opening it has none yet.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from .perf import PerfMonitor

PLOTTED = (("frame_ms", "frame (wall)"), ("cpu_ms", "CPU"), ("gpu_ms", "GPU"), ("record_ms", "record"))
REFRESH_S = 0.25
PLOT_POINTS = 120  # per line: implot's cost and the UI's vertex count grow with points drawn


class PerfOverlay:
    def __init__(self) -> None:
        from imgui_bundle import imgui, implot

        self.imgui = imgui
        self.implot = implot
        self._next_refresh = 0.0
        self._fps = float("nan")
        self._warmup = ""  # what the FPS line says while the monitor has no rate yet
        self._rows: list[tuple[str, str, str, str]] = []
        self.systems: list[tuple[str, str, str]] = []  # (system, mean ms, thread) slowest first, as drawn
        self.passes: list[tuple[str, str]] = []  # (GPU pass, mean ms) slowest first, as drawn
        self._lines: list[tuple[str, np.ndarray, np.ndarray]] = []
        self._gauges: list[str] = []  # the resources' own lines (the sound's)
        self._limits = (0.0, 1.0, 1.0)  # x from, x to, y top
        self.visible = False  # drawn last frame (not collapsed, its tab shown): the run loop times systems then

    def _refresh(self, perf: PerfMonitor) -> None:
        now = time.perf_counter()
        if now < self._next_refresh:
            return
        self._next_refresh = now + REFRESH_S
        self._fps = perf.fps
        self._warmup = fps_placeholder(perf)
        self._rows = []
        for name, label in PLOTTED[1:]:
            s = perf.stats(name)
            self._rows.append((label, _ms(s.min), _ms(s.mean), _ms(s.p99)))
        threads = perf.system_threads
        self.systems = [(x.name, _ms(x.mean), _thread(threads.get(x.name, ""))) for x in perf.system_times()]
        self.passes = [(x.name, _ms(x.mean)) for x in perf.gpu_pass_times()]
        self._gauges = perf.gauge_lines()
        t = perf.times()
        self._lines = []
        top = 1.0
        for name, label in PLOTTED:
            y = perf.series(name)
            ok = np.isfinite(y)
            if ok.sum() > 1:
                self._lines.append((label, *_peaks(t[ok], y[ok], PLOT_POINTS)))
                top = max(top, float(np.percentile(y[ok], 99)) * 1.2)
        self._limits = (float(t[0]), float(t[-1]), top) if len(t) > 1 else (0.0, 1.0, 1.0)

    def draw(self, perf: PerfMonitor, overlay_ms: float) -> None:
        """The Perf window; `overlay_ms`: what the UI cost last frame (build, copy, record)."""
        imgui = self.imgui
        io = imgui.get_io()
        imgui.set_next_window_pos((io.display_size.x - 370, 10), imgui.Cond_.first_use_ever.value)
        imgui.set_next_window_size((360, 330), imgui.Cond_.first_use_ever.value)
        self._refresh(perf)
        self.visible = imgui.begin("Perf")[0]
        if self.visible:
            imgui.text(self._warmup or f"FPS {self._fps:7.1f}   (wall clock)")
            if imgui.begin_table("ms", 4, imgui.TableFlags_.borders_inner_h.value):
                for title in ("ms", "min", "mean", "p99"):
                    imgui.table_setup_column(title)
                imgui.table_headers_row()
                for row in self._rows:
                    imgui.table_next_row()
                    for i, text in enumerate(row):
                        imgui.table_set_column_index(i)
                        imgui.text(text)
                imgui.end_table()
            # short lines: the window is 300 pixels wide in the editor's narrow layout
            imgui.text(f"CPU system {_ms(perf.cpu_system_percent, '5.1f')}%")
            per_core = _ms(perf.cpu_process_percent_per_core, ".1f")
            imgui.text(f"    process {_ms(perf.cpu_process_percent, '5.1f')}% ({per_core}%/core)")
            imgui.text(f"resident memory {perf.rss_bytes / 2**20:.1f} MiB")
            imgui.text(f"overlay {overlay_ms:.3f} ms, monitor {_ms(perf.overhead_ms * 1e3, '.1f')} us")
            for line in self._gauges:
                imgui.text(line)
            self._table("systems", ("system", "CPU ms", "thread"), self.systems)
            self._table("GPU passes", ("GPU pass", "ms"), self.passes)
            self._plot(perf)
        imgui.end()

    def _table(self, what: str, titles: tuple[str, ...], rows: Sequence[tuple[str, ...]]) -> None:
        """One list: means per frame over the window, slowest first."""
        imgui = self.imgui
        if not rows:
            imgui.text_disabled(f"{what}: none timed yet")  # short: the narrow layout
            return
        if imgui.begin_table(what, len(titles), imgui.TableFlags_.borders_inner_h.value):
            for title in titles:
                imgui.table_setup_column(title)
            imgui.table_headers_row()
            for row in rows:
                imgui.table_next_row()
                for i, text in enumerate(row):
                    imgui.table_set_column_index(i)
                    imgui.text(text)
            imgui.end_table()

    def _plot(self, perf: PerfMonitor) -> None:
        implot = self.implot
        if not self._lines:
            return
        x0, x1, top = self._limits
        if implot.begin_plot("##frame times", (-1, 150)):
            implot.setup_axes("s", "ms")
            implot.setup_axis_limits(implot.ImAxis_.x1.value, x0, x1, implot.Cond_.always.value)
            implot.setup_axis_limits(implot.ImAxis_.y1.value, 0.0, top, implot.Cond_.always.value)
            for label, x, y in self._lines:
                implot.plot_line(label, x, y)
            implot.end_plot()


def fps_placeholder(perf: PerfMonitor) -> str:
    """The FPS line while there is no rate yet (warm-up frames, or one frame: no interval); ""
    once there is one."""
    if perf.warming_up:
        return f"FPS -   (warm-up: {perf.frame_count} of {perf.warmup_frames} left out)"
    return "FPS -   (measuring)" if not np.isfinite(perf.fps) else ""


def _peaks(t: np.ndarray, y: np.ndarray, points: int) -> tuple[np.ndarray, np.ndarray]:
    """At most `points` samples: the largest of each run of neighbours, so a spike stays visible."""
    if len(y) <= points:
        return np.ascontiguousarray(t), np.ascontiguousarray(y)
    starts = np.linspace(0, len(y), points, endpoint=False).astype(np.int64)
    return np.ascontiguousarray(t[starts]), np.maximum.reduceat(y, starts)


def _thread(name: str) -> str:
    """A thread's name, short: the main thread, or the pool's worker (jobs.py names them)."""
    if name == "MainThread":
        return "main"
    if name.startswith("ecs-job-"):
        return f"worker {name.removeprefix('ecs-job-')}"
    return name or "-"


def _ms(value: float, spec: str = ".3f") -> str:
    return "-" if not np.isfinite(value) else format(value, spec)
