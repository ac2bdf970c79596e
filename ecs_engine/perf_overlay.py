"""The Perf window: the PerfMonitor's numbers as ImGui text and implot rolling plots.

FPS is wall clock; CPU frame, record and GPU ms (timestamps) come with min, mean and 99th
percentile over the window; CPU system and process % (raw and per core) and resident memory
come from psutil samples taken about 4 times a second; the overlay's own cost is shown too.
"""

from __future__ import annotations

import numpy as np

from .perf import PerfMonitor

PLOTTED = (("frame_ms", "frame (wall)"), ("cpu_ms", "CPU"), ("gpu_ms", "GPU"), ("record_ms", "record"))


class PerfOverlay:
    def __init__(self) -> None:
        from imgui_bundle import imgui, implot

        self.imgui = imgui
        self.implot = implot

    def draw(self, perf: PerfMonitor, overlay_ms: float) -> None:
        """The Perf window; `overlay_ms`: what the UI cost last frame (build, copy, record)."""
        imgui, implot = self.imgui, self.implot
        io = imgui.get_io()
        imgui.set_next_window_pos((io.display_size.x - 370, 10), imgui.Cond_.first_use_ever.value)
        imgui.set_next_window_size((360, 330), imgui.Cond_.first_use_ever.value)
        if imgui.begin("Perf")[0]:
            imgui.text(f"FPS {perf.fps:7.1f}   (wall clock)")
            if imgui.begin_table("ms", 4, imgui.TableFlags_.borders_inner_h.value):
                for title in ("ms", "min", "mean", "p99"):
                    imgui.table_setup_column(title)
                imgui.table_headers_row()
                for name, label in PLOTTED[1:]:
                    s = perf.stats(name)
                    imgui.table_next_row()
                    for i, text in enumerate((label, _ms(s.min), _ms(s.mean), _ms(s.p99))):
                        imgui.table_set_column_index(i)
                        imgui.text(text)
                imgui.end_table()
            imgui.text(f"CPU system {perf.cpu_system_percent:5.1f}%   process {perf.cpu_process_percent:6.1f}% "
                       f"({perf.cpu_process_percent_per_core:4.1f}%/core)")
            imgui.text(f"resident memory {perf.rss_bytes / 2**20:7.1f} MiB")
            imgui.text(f"overlay cost {overlay_ms:.3f} ms   monitor {perf.overhead_ms * 1e3:.1f} us")
            self._plot(perf)
        imgui.end()

    def _plot(self, perf: PerfMonitor) -> None:
        implot = self.implot
        t = perf.times()
        if len(t) < 2:
            return
        lines = []
        top = 1.0
        for name, label in PLOTTED:
            y = perf.series(name)
            ok = np.isfinite(y)
            if ok.any():
                lines.append((label, np.ascontiguousarray(t[ok]), np.ascontiguousarray(y[ok])))
                top = max(top, float(np.percentile(y[ok], 99)) * 1.2)
        if implot.begin_plot("##frame times", (-1, 150)):
            implot.setup_axes("s", "ms")
            implot.setup_axis_limits(implot.ImAxis_.x1.value, float(t[0]), float(t[-1]), implot.Cond_.always.value)
            implot.setup_axis_limits(implot.ImAxis_.y1.value, 0.0, top, implot.Cond_.always.value)
            for label, x, y in lines:
                implot.plot_line(label, x, y)
            implot.end_plot()


def _ms(value: float) -> str:
    return "-" if not np.isfinite(value) else f"{value:.3f}"

