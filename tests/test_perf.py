"""The performance monitor on simulated time: FPS from wall intervals, the rolling window,
statistics, psutil sampling rate, the headless summary and the --perf-json file."""

from __future__ import annotations

import json
import math
import os
import time
import warnings

import numpy as np
import pytest

from ecs_engine.app.perf import (
    METRICS,
    WARMUP_FRAMES,
    PerfLog,
    PerfMonitor,
    ProcessSample,
    PsutilSampler,
    Stats,
    check_writable,
)
from ecs_engine.errors import UsageError

MiB = 2**20


class FakeClock:
    def __init__(self, t: float = 1000.0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t


class FakeSampler:
    """Fixed values; remembers the clock time of every call."""

    def __init__(
        self,
        clock: FakeClock | None = None,
        cores: int = 16,
        system: float = 6.0,
        process: float = 101.0,
        rss: int = 210 * MiB,
    ) -> None:
        self.clock = clock
        self.cores = cores
        self.value = ProcessSample(system, process, rss)
        self.calls: list[float] = []

    def sample(self) -> ProcessSample:
        self.calls.append(self.clock() if self.clock else math.nan)
        return self.value


def monitor(clock: FakeClock, **kwargs) -> tuple[PerfMonitor, FakeSampler]:
    """A monitor on `clock`; every frame counts unless `warmup_frames` is given."""
    sampler = kwargs.pop("sampler", None) or FakeSampler(clock)
    kwargs.setdefault("warmup_frames", 0)
    return PerfMonitor(clock=clock, sampler=sampler, **kwargs), sampler


def run(mon: PerfMonitor, clock: FakeClock, frames: int, dt: float, **frame_args) -> None:
    frame_args.setdefault("cpu_ms", 1.0)
    for _ in range(frames):
        clock.t += dt
        mon.frame(**frame_args)


# -- frame rate and window -----------------------------------------------------------------------


def test_fps_is_frames_over_wall_time_and_ignores_cpu_time():
    rates = []
    for cpu_ms in (0.1, 50.0):  # CPU time far below and far above the 2 ms wall interval
        clock = FakeClock()
        mon, _ = monitor(clock)
        run(mon, clock, 1000, 0.002, cpu_ms=cpu_ms)
        rates.append(mon.fps)
        assert mon.stats("cpu_ms") == Stats(cpu_ms, pytest.approx(cpu_ms), pytest.approx(cpu_ms))
    assert rates[0] == pytest.approx(500.0, rel=1e-9)
    assert rates[1] == pytest.approx(500.0, rel=1e-9)
    assert mon.stats("frame_ms") == pytest.approx(Stats(2.0, 2.0, 2.0), rel=1e-6)


def test_fps_counts_uneven_intervals_as_frames_over_elapsed_time():
    clock = FakeClock()
    mon, _ = monitor(clock)
    for dt in (0.010, 0.030, 0.010, 0.030):  # 4 intervals in 80 ms: 50 fps, not mean(1/dt)
        clock.t += dt
        mon.frame(1.0)
    assert mon.fps == pytest.approx(3 / 0.070)  # the first frame has no interval
    clock.t += 0.010
    mon.frame(1.0)
    assert mon.fps == pytest.approx(4 / 0.080)


def test_first_frame_has_no_interval_and_empty_monitor_is_nan():
    clock = FakeClock()
    mon, _ = monitor(clock)
    assert math.isnan(mon.fps) and math.isnan(mon.overhead_ms)
    for name in METRICS:
        assert all(math.isnan(x) for x in mon.stats(name))
        assert mon.series(name).dtype == np.float64 and mon.series(name).size == 0
    assert mon.times().size == 0
    clock.t += 0.5
    mon.frame(3.0)
    assert math.isnan(mon.series("frame_ms")[0])
    assert all(math.isnan(x) for x in mon.stats("frame_ms"))
    assert math.isnan(mon.fps)
    assert mon.stats("cpu_ms") == Stats(3.0, 3.0, 3.0)
    assert mon.times().tolist() == [pytest.approx(0.5)]  # seconds since the monitor was made


def test_window_drops_old_samples():
    clock = FakeClock()
    mon, _ = monitor(clock, window_s=5.0)
    run(mon, clock, 5000, 0.001, cpu_ms=10.0, gpu_ms=10.0)  # 5 s at 1000 fps, slow frames
    assert mon.fps == pytest.approx(1000.0)
    run(mon, clock, 2750, 0.002, cpu_ms=1.0, gpu_ms=2.0)  # 5.5 s at 500 fps
    assert mon.stats("cpu_ms") == Stats(1.0, 1.0, 1.0)
    assert mon.stats("gpu_ms") == Stats(2.0, 2.0, 2.0)
    assert mon.fps == pytest.approx(500.0, rel=1e-6)
    times = mon.times()
    assert 2500 <= times.size <= 2501
    assert times[-1] == pytest.approx(10.5)
    assert times[-1] - times[0] <= 5.0 + 1e-9
    assert np.all(np.diff(times) > 0)  # oldest first
    assert mon.frame_count == 7750


def test_series_and_times_are_aligned_oldest_first_across_the_ring_seam():
    clock = FakeClock()
    mon, _ = monitor(clock, window_s=1.0, max_fps=100.0)  # ring of 116 rows, wraps many times
    for k in range(1000):
        clock.t += 0.01
        mon.frame(cpu_ms=float(k), record_ms=2.0 * k, wait_ms=0.5)
    cpu = mon.series("cpu_ms")
    assert mon.capacity == 116
    assert 100 <= cpu.size <= 101
    assert cpu.tolist() == list(range(1000 - cpu.size, 1000))
    np.testing.assert_allclose(mon.series("record_ms"), 2 * cpu)
    np.testing.assert_allclose(mon.times(), (cpu + 1) * 0.01, rtol=1e-9)
    assert mon.stats("wait_ms") == Stats(0.5, 0.5, 0.5)
    cpu[:] = -1  # a copy: the caller may keep or change it
    assert mon.series("cpu_ms")[0] != -1


def test_stats_match_numpy_on_known_data():
    rng = np.random.default_rng(7)
    values = rng.gamma(2.0, 1.5, 3000)
    clock = FakeClock()
    mon, _ = monitor(clock, window_s=10.0)
    for v in values:
        clock.t += 0.001
        mon.frame(cpu_ms=float(v), record_ms=float(v) / 4)
    got = mon.stats("cpu_ms")
    assert isinstance(got, Stats)
    assert got.min == pytest.approx(values.min())
    assert got.mean == pytest.approx(values.mean())
    assert got.p99 == pytest.approx(np.percentile(values, 99))
    assert got.p99 < values.max()  # a percentile, not the maximum
    assert mon.stats("record_ms").p99 == pytest.approx(np.percentile(values / 4, 99))
    np.testing.assert_array_equal(mon.series("cpu_ms"), values)


@pytest.mark.parametrize("n", [1, 2, 3, 99, 100, 101, 1234])
def test_p99_matches_numpy_for_every_size_with_gaps(n):
    rng = np.random.default_rng(n)
    values = rng.gamma(2.0, 1.5, n)
    missing = rng.random(n) < 0.3
    missing[0] = False
    clock = FakeClock()
    mon, _ = monitor(clock)
    for v, skip in zip(values, missing, strict=True):
        clock.t += 0.001
        mon.frame(cpu_ms=1.0, gpu_ms=None if skip else float(v))
    known = values[~missing]
    got = mon.stats("gpu_ms")
    assert got == pytest.approx(Stats(known.min(), known.mean(), np.percentile(known, 99)), rel=1e-12)
    assert np.isnan(mon.series("gpu_ms")).sum() == missing.sum()  # stats left the window alone


def test_missing_gpu_times_are_left_out_of_gpu_stats_but_frames_count():
    clock = FakeClock()
    mon, _ = monitor(clock)
    gpu = [None if k % 3 else float(k) for k in range(300)]
    for g in gpu:
        clock.t += 0.002
        mon.frame(cpu_ms=1.0, gpu_ms=g)
    known = np.array([g for g in gpu if g is not None])
    assert mon.stats("gpu_ms") == pytest.approx(Stats(known.min(), known.mean(), np.percentile(known, 99)))
    series = mon.series("gpu_ms")
    assert series.size == 300 and np.isnan(series).sum() == 200
    assert mon.fps == pytest.approx(500.0, rel=1e-6)
    assert mon.frame_count == 300


def test_no_gpu_time_at_all_gives_nan_stats_without_warnings():
    clock = FakeClock()
    mon, _ = monitor(clock)
    run(mon, clock, 50, 0.002)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = mon.stats("gpu_ms")
    assert all(math.isnan(x) for x in got)
    assert "gpu n/a" in mon.summary_line()


def test_unknown_metric_and_bad_settings_are_refused():
    clock = FakeClock()
    mon, _ = monitor(clock)
    with pytest.raises(ValueError, match="unknown metric 'fps_ms'"):
        mon.stats("fps_ms")
    with pytest.raises(ValueError, match="unknown metric"):
        mon.series("t")
    for bad in ({"window_s": 0.0}, {"sample_hz": -1.0}, {"max_fps": 0.0}):
        with pytest.raises(ValueError, match="must be positive"):
            PerfMonitor(clock=clock, sampler=FakeSampler(clock), **bad)


def test_latest_counters_are_those_of_the_last_frame():
    clock = FakeClock()
    mon, _ = monitor(clock)
    clock.t += 0.01
    mon.frame(1.0, draws=3, visible=10)
    clock.t += 0.01
    mon.frame(1.0, draws=2, visible=100, triangles=1200)
    assert mon.counters == {"draws": 2, "visible": 100, "triangles": 1200}


# -- warm-up ---------------------------------------------------------------------------------------


def test_warm_up_frames_stay_out_of_the_window_the_summary_and_the_logs_figures(tmp_path):
    """The first frames (6.5 s of pipeline creation and JIT on the 2-core box) would make the
    rolling CPU mean seconds long for the whole window: they are logged but not counted."""
    assert PerfMonitor().warmup_frames == WARMUP_FRAMES == 5  # what a run's monitor gets (loop.py)
    clock = FakeClock()
    mon, _ = monitor(clock, warmup_frames=5, log=tmp_path / "perf.json")
    assert mon.warming_up
    for cpu in (6500.0, 900.0, 40.0, 30.0):
        clock.t += cpu / 1e3
        mon.frame(cpu_ms=cpu, gpu_ms=cpu / 2)
    assert mon.warming_up and mon.frame_count == 4
    assert math.isnan(mon.fps) and math.isnan(mon.stats("cpu_ms").mean)
    assert mon.summary_line().startswith("warm-up frame 4 of 5 (left out of the figures) | sys 6%")
    clock.t += 0.02
    mon.frame(cpu_ms=20.0)  # the last warm-up frame
    assert not mon.warming_up and mon.series("cpu_ms").size == 0
    run(mon, clock, 100, 0.002, cpu_ms=1.0, gpu_ms=0.5)
    assert mon.stats("cpu_ms") == Stats(1.0, 1.0, 1.0)
    assert mon.stats("gpu_ms") == Stats(0.5, 0.5, 0.5)
    assert mon.fps == pytest.approx(500.0)  # the first counted frame's interval starts at the last warm-up frame
    assert mon.summary_line().startswith("fps 500 | cpu 1.00 ms (p99 1.00) | record 0.00 | gpu 0.50 ms")
    mon.write_json()
    doc = json.loads((tmp_path / "perf.json").read_text())
    assert len(doc["frames"]) == 105 and doc["frames"][0]["cpu_ms"] == 6500.0  # every frame is kept
    assert doc["warmup_frames"] == 5
    assert doc["summary"]["cpu_ms"] == {"min": 1.0, "mean": 1.0, "p99": 1.0}
    assert doc["fps"] == pytest.approx(500.0)


def test_a_run_shorter_than_the_warm_up_summarises_every_frame(tmp_path):
    clock = FakeClock()
    mon, _ = monitor(clock, warmup_frames=5, log=True)
    run(mon, clock, 3, 0.01, cpu_ms=2.0)
    doc = mon.log.to_dict({}, 16, mon.warmup_frames)
    assert doc["warmup_frames"] == 0 and doc["summary"]["cpu_ms"]["mean"] == 2.0
    with pytest.raises(ValueError, match="warmup_frames"):
        PerfMonitor(clock=clock, sampler=FakeSampler(clock), warmup_frames=-1)


def test_the_perf_windows_fps_line_never_shows_nan():
    from ecs_engine.app.perf_overlay import fps_placeholder

    clock = FakeClock()
    mon, _ = monitor(clock, warmup_frames=2)
    lines = []
    for _ in range(5):
        lines.append(fps_placeholder(mon) or f"FPS {mon.fps:7.1f}")
        clock.t += 0.01
        mon.frame(1.0)
    assert "nan" not in " ".join(lines).lower()
    assert lines[:2] == [
        "FPS -   (warm-up: 0 of 2 left out)",
        "FPS -   (warm-up: 1 of 2 left out)",
    ]
    assert lines[2:] == ["FPS -   (measuring)", "FPS   100.0", "FPS   100.0"]


# -- ring capacity ---------------------------------------------------------------------------------


def test_ring_keeps_every_sample_of_the_window_at_4000_fps():
    clock = FakeClock()
    mon, _ = monitor(clock, window_s=5.0)
    start = mon.capacity
    for k in range(1, 24001):  # 6 s at 4000 fps
        clock.t = 1000.0 + k / 4000
        mon.frame(cpu_ms=float(k))
    cpu = mon.series("cpu_ms")
    assert start < 20000 <= mon.capacity <= mon.max_rows
    assert 20000 <= cpu.size <= 20001
    assert cpu.tolist() == list(range(24001 - cpu.size, 24001))  # no hole, oldest first
    assert mon.fps == pytest.approx(4000.0, rel=1e-6)


def test_ring_grows_only_as_needed_and_is_capped():
    clock = FakeClock()
    slow, _ = monitor(clock)
    run(slow, clock, 60 * 60, 1 / 60)  # a minute at 60 fps: 300 frames a window
    assert slow.capacity == 1024
    assert 300 <= slow.times().size <= 301

    fast, _ = monitor(clock, window_s=1.0, max_fps=1000.0)
    run(fast, clock, 8000, 1 / 4000)  # 4x faster than max_fps: the last max_rows frames are kept
    assert fast.capacity == fast.max_rows == 1016
    assert fast.times().size == 1016
    assert fast.fps == pytest.approx(4000.0, rel=1e-6)


def test_ring_grows_in_age_order_when_the_rate_rises_mid_run():
    clock = FakeClock()
    mon, _ = monitor(clock, window_s=5.0)
    run(mon, clock, 1500, 0.01, cpu_ms=-1.0)  # 100 fps: 500 frames a window, the ring wraps
    assert mon.capacity == 1024
    for k in range(3000):  # then 1000 fps: the ring must grow with its oldest row mid-array
        clock.t += 0.001
        mon.frame(cpu_ms=float(k))
    assert mon.capacity == 4096
    times = mon.times()
    assert np.all(np.diff(times) > 0)
    cpu = mon.series("cpu_ms")
    assert cpu[-3000:].tolist() == list(range(3000))
    assert (cpu[:-3000] == -1.0).all() and 200 <= cpu.size - 3000 <= 201  # 2 s of the old rate


# -- psutil sampling --------------------------------------------------------------------------------


def test_psutil_is_sampled_about_four_times_a_second_not_every_frame():
    clock = FakeClock()
    mon, sampler = monitor(clock, sample_hz=4.0)
    run(mon, clock, 2000, 0.001)  # 2 s at 1000 fps
    assert 8 <= len(sampler.calls) <= 9
    assert np.all(np.diff(sampler.calls) >= 0.25 - 1e-9)


def test_sampling_resumes_at_its_rate_after_a_stall():
    clock = FakeClock()
    mon, sampler = monitor(clock, sample_hz=4.0)
    run(mon, clock, 1000, 0.001)
    clock.t += 3.0  # a 3 s hitch (loading, a breakpoint): one sample, not twelve in a row
    run(mon, clock, 1000, 0.001)
    assert np.all(np.diff(sampler.calls) >= 0.25 - 1e-9)
    assert 8 <= len(sampler.calls) <= 10


def test_process_percent_raw_and_per_core():
    clock = FakeClock()
    mon, _ = monitor(clock, sampler=FakeSampler(clock, cores=8, system=12.0, process=340.0, rss=123456789))
    assert math.isnan(mon.cpu_process_percent) and mon.rss_bytes == 0  # nothing sampled yet
    clock.t += 0.01
    mon.frame(1.0)
    assert mon.cpu_system_percent == 12.0
    assert mon.cpu_process_percent == 340.0  # can exceed 100
    assert mon.cpu_process_percent_per_core == pytest.approx(340.0 / 8)
    assert mon.rss_bytes == 123456789


def test_real_psutil_sampler_gives_finite_values():
    mon = PerfMonitor(warmup_frames=0)
    mon.frame(cpu_ms=1.0, record_ms=0.5, gpu_ms=None, wait_ms=0.1, draws=1)
    assert mon.cores >= 1
    for value in (mon.cpu_system_percent, mon.cpu_process_percent, mon.cpu_process_percent_per_core):
        assert math.isfinite(value) and value >= 0
    assert mon.cpu_process_percent_per_core == pytest.approx(mon.cpu_process_percent / mon.cores)
    assert mon.rss_bytes > 1 * MiB
    assert math.isfinite(mon.overhead_ms)


def test_psutil_sampler_primes_cpu_percent_so_later_samples_measure_work():
    sampler = PsutilSampler()
    end = time.process_time() + 0.2
    while time.process_time() < end:  # burn CPU so the process % must be well above zero
        pass
    s = sampler.sample()
    assert s.cpu_process_percent > 1.0  # unprimed, the first call returns exactly 0.0
    assert 0.0 <= s.cpu_system_percent <= 100.0


# -- overhead and summary ------------------------------------------------------------------------------


def test_overhead_is_measured_and_small():
    clock = FakeClock()
    mon, _ = monitor(clock)
    run(mon, clock, 2000, 0.001, gpu_ms=0.5, draws=1, visible=2)
    assert 0.0 < mon.overhead_ms < 1.0  # a few microseconds in practice
    assert mon.overhead_total_s > 0.0
    assert mon.stats("overhead_ms").min > 0.0
    assert mon.series("overhead_ms").size == 2000


def test_summary_due_once_per_second():
    clock = FakeClock()
    mon, _ = monitor(clock)
    due_at = []
    for _ in range(3500):  # 3.5 s at 1000 fps
        clock.t += 0.001
        mon.frame(1.0)
        if mon.summary_due():
            due_at.append(clock.t - 1000.0)
    assert len(due_at) == 3
    np.testing.assert_allclose(due_at, [1.0, 2.0, 3.0], atol=0.0015)
    assert not mon.summary_due()  # asking again in the same instant: not due


def test_summary_due_after_a_stall_is_not_repeated():
    clock = FakeClock()
    mon, _ = monitor(clock)
    clock.t += 4.5
    assert mon.summary_due()
    assert not mon.summary_due()
    clock.t += 0.9
    assert not mon.summary_due()
    clock.t += 0.2
    assert mon.summary_due()


def test_summary_line_has_the_numbers():
    clock = FakeClock()
    mon, _ = monitor(clock)
    assert mon.summary_line() == "fps n/a | cpu n/a ms (p99 n/a) | record n/a | gpu n/a | sys n/a"
    run(mon, clock, 500, 0.001, cpu_ms=0.41, record_ms=0.08, gpu_ms=0.37, draws=2, visible=100)
    assert mon.summary_line() == (
        "fps 1000 | cpu 0.41 ms (p99 0.41) | record 0.08 | gpu 0.37 ms | "
        "sys 6% proc 101% (6.3%/core) | rss 210 MiB | 100 drawn in 2 draws"
    )
    clock.t += 0.001
    mon.frame(cpu_ms=5.0, entities=7)
    line = mon.summary_line()
    cpu = np.array([0.41] * 500 + [5.0])
    assert f"cpu {cpu.mean():.2f} ms (p99 {np.percentile(cpu, 99):.2f})" in line  # 0.42 and 0.46
    assert "entities 7" in line and "drawn" not in line


# -- the --perf-json log -----------------------------------------------------------------------------


def test_json_round_trip(tmp_path):
    path = tmp_path / "perf.json"
    clock = FakeClock()
    mon, sampler = monitor(clock, log=path, window_s=1.0)
    gpu = [None, 0.5, None, 0.25] * 500  # 2000 frames over 6 s: more than the window
    times = [0.002 * (k + 1) if k < 1000 else 2.0 + 0.004 * (k - 999) for k in range(2000)]
    for k, g in enumerate(gpu):
        clock.t = 1000.0 + times[k]
        mon.frame(cpu_ms=1.0 + k % 7, record_ms=0.25, gpu_ms=g, wait_ms=0.125, draws=2, visible=k)
    mon.write_json(meta={"scene": "cubes", "count": 100})
    doc = json.loads(path.read_text())
    assert set(doc) == {"schema_version", "meta", "frames", "psutil", "warmup_frames", "summary", "fps"}
    assert doc["warmup_frames"] == 0
    assert doc["schema_version"] == 1
    assert doc["meta"] == {"scene": "cubes", "count": 100, "logical_cores": 16}
    frames = doc["frames"]
    assert len(frames) == 2000 == mon.frame_count
    assert set(frames[1]) == {"t", "frame_ms", "cpu_ms", "record_ms", "gpu_ms", "wait_ms", "draws", "visible"}
    assert frames[0]["frame_ms"] is None and frames[0]["gpu_ms"] is None
    assert frames[1]["frame_ms"] == pytest.approx(2.0) and frames[1]["gpu_ms"] == 0.5
    assert [f["gpu_ms"] for f in frames] == gpu
    assert [f["visible"] for f in frames] == list(range(2000))
    assert isinstance(frames[5]["draws"], int)
    assert [f["t"] for f in frames] == pytest.approx(times)
    assert frames[1500]["frame_ms"] == pytest.approx(4.0)
    assert frames[3] == pytest.approx(
        {
            "t": 0.008,
            "frame_ms": 2.0,
            "cpu_ms": 4.0,
            "record_ms": 0.25,
            "gpu_ms": 0.25,
            "wait_ms": 0.125,
            "draws": 2,
            "visible": 3,
        }
    )
    assert len(doc["psutil"]) == len(sampler.calls)
    assert doc["psutil"][0] == {
        "t": pytest.approx(0.002),
        "cpu_system_percent": 6.0,
        "cpu_process_percent": 101.0,
        "cpu_process_percent_per_core": pytest.approx(101.0 / 16),
        "rss_bytes": 210 * MiB,
    }
    cpu = np.array([1.0 + k % 7 for k in range(2000)])
    assert doc["summary"]["cpu_ms"] == pytest.approx({"min": 1.0, "mean": cpu.mean(), "p99": np.percentile(cpu, 99)})
    gpu_p99 = np.percentile([0.5, 0.25] * 500, 99)
    assert doc["summary"]["gpu_ms"] == pytest.approx({"min": 0.25, "mean": 0.375, "p99": gpu_p99})
    assert set(doc["summary"]) == set(METRICS)
    assert doc["fps"] == pytest.approx(1999 / (times[-1] - times[0]))  # the whole run, not the window
    assert mon.fps == pytest.approx(250.0)
    assert os.listdir(tmp_path) == ["perf.json"]  # no temporary or probe file left behind


def test_json_has_nulls_not_nan_and_replaces_an_old_file(tmp_path):
    path = tmp_path / "perf.json"
    path.write_text("old")
    clock = FakeClock()
    mon, _ = monitor(clock, log=True)
    clock.t += 0.01
    mon.frame(1.0)  # one frame: no interval, no gpu, no fps
    mon.write_json(path)
    text = path.read_text()
    assert "NaN" not in text
    doc = json.loads(text)
    assert doc["fps"] is None
    assert doc["summary"]["gpu_ms"] == {"min": None, "mean": None, "p99": None}
    assert doc["frames"] == [
        {"t": pytest.approx(0.01), "frame_ms": None, "cpu_ms": 1.0, "record_ms": 0.0, "gpu_ms": None, "wait_ms": 0.0}
    ]
    assert doc["meta"] == {"logical_cores": 16}


def test_log_keeps_every_frame_across_chunks():
    log = PerfLog()
    clock = FakeClock()
    mon = PerfMonitor(clock=clock, sampler=FakeSampler(clock))
    mon.log = log
    n = 2 * PerfLog.CHUNK + 5
    for k in range(n):
        clock.t += 0.001
        counters = {"visible": k} if k >= PerfLog.CHUNK else {}  # a counter that starts late
        mon.frame(cpu_ms=float(k), **counters)
    rows, counters = log.columns()
    assert len(log) == n == rows.shape[0]
    assert rows[:, 2].tolist() == list(range(n))
    assert np.isnan(counters["visible"][: PerfLog.CHUNK]).all()
    assert counters["visible"][PerfLog.CHUNK :].tolist() == list(range(PerfLog.CHUNK, n))
    assert (rows[:, -1] > 0).all()  # each frame's own cost is recorded


def test_write_json_needs_a_log_and_a_path(tmp_path):
    clock = FakeClock()
    mon, _ = monitor(clock)
    with pytest.raises(ValueError, match="log=True"):
        mon.write_json(tmp_path / "x.json")
    mon, _ = monitor(clock, log=True)
    with pytest.raises(ValueError, match="needs a path"):
        mon.write_json()


@pytest.mark.parametrize("bad", ["file/perf.json", "/proc/no-such-dir/perf.json", "dir", ""])
def test_unwritable_log_path_fails_at_construction(tmp_path, bad):
    (tmp_path / "file").write_text("a regular file")
    (tmp_path / "dir").mkdir()
    path = str(tmp_path / bad) if bad and not bad.startswith("/") else bad
    clock = FakeClock()
    with pytest.raises(UsageError) as info:
        PerfMonitor(clock=clock, sampler=FakeSampler(clock), log=path)
    message = str(info.value)
    assert "\n" not in message and "performance log" in message
    assert path in message
    with pytest.raises(UsageError):
        check_writable(path)


def test_check_writable_accepts_a_good_path_and_leaves_nothing(tmp_path):
    target = tmp_path / "out.json"
    assert check_writable(str(target)) == target
    assert os.listdir(tmp_path) == []


def test_write_failing_at_the_end_names_the_path_and_leaves_no_temp_file(tmp_path):
    folder = tmp_path / "gone"
    folder.mkdir()
    clock = FakeClock()
    mon, _ = monitor(clock, log=folder / "perf.json")
    run(mon, clock, 10, 0.01)
    (tmp_path / "elsewhere").mkdir()
    target = tmp_path / "elsewhere" / "perf.json"
    target.mkdir()  # os.replace cannot put a file over a directory
    with pytest.raises(UsageError, match=r"elsewhere/perf\.json: cannot write the performance log"):
        mon.write_json(target)
    assert os.listdir(tmp_path / "elsewhere") == ["perf.json"]
    folder.rmdir()
    with pytest.raises(UsageError, match=r"gone/perf\.json"):
        mon.write_json()


def test_a_failed_write_keeps_the_old_file_whole(tmp_path):
    path = tmp_path / "perf.json"
    path.write_text("previous run")
    clock = FakeClock()
    mon, _ = monitor(clock, log=path)
    run(mon, clock, 10, 0.01)
    with pytest.raises(TypeError):
        mon.write_json(meta={"not json": object()})  # fails halfway through the dump
    assert path.read_text() == "previous run"
    assert os.listdir(tmp_path) == ["perf.json"]
