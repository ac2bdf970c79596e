"""Profiling without a GPU: the schedule reports each system's run on the thread that ran it, the
worker pool each job, the Perf monitor keeps rolling means by name (warm-up left out), and the
trace recorder keeps a ring of frames and places GPU frames on the CPU's clock."""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest

from ecs_engine import system
from ecs_engine.app.perf import PerfMonitor, ProcessSample, Timings
from ecs_engine.app.trace import TraceRecorder, gpu_clock
from ecs_engine.components import Transform, Velocity
from ecs_engine.ecs import schedule as schedule_module
from ecs_engine.ecs.schedule import Schedule
from ecs_engine.ecs.world import World
from ecs_engine.gpu.frames import GpuFrame
from ecs_engine.jobs import JobPool


class Recorder:
    def __init__(self) -> None:
        self.runs: list[tuple[str, str, int, int]] = []
        self.jobs: list[tuple[str, str]] = []

    def system(self, name: str, start_ns: int, end_ns: int) -> None:
        self.runs.append((name, threading.current_thread().name, start_ns, end_ns))

    def job(self, name: str, start_ns: int, end_ns: int) -> None:
        self.jobs.append((name, threading.current_thread().name))


def busy(world, dt):
    sum(range(2000))


def idle(world, dt):
    pass


def test_a_timed_schedule_reports_each_system_run_with_its_clock_span():
    world, sched = World(), Schedule()
    sched.add(busy)
    sched.add(idle, stage="post_update")
    sched.timer = timer = Recorder()
    sched.run(world, 1 / 60)
    assert [(name, thread) for name, thread, *_ in timer.runs] == [("busy", "MainThread"), ("idle", "MainThread")]
    assert all(end >= start > 0 for *_, start, end in timer.runs)
    assert timer.runs[0][3] <= timer.runs[1][2]  # in the order they ran


def test_an_untimed_schedule_reads_no_clock(monkeypatch):
    def clock() -> int:
        raise AssertionError("the clock was read with no timer")

    monkeypatch.setattr(schedule_module, "perf_counter_ns", clock)
    world, sched = World(), Schedule()
    sched.add(busy)
    sched.run(world, 1 / 60)  # no timer: nothing reads the clock
    sched.timer = Recorder()
    with pytest.raises(AssertionError, match="no timer"):
        sched.run(world, 1 / 60)


def test_a_parallel_stage_reports_systems_on_the_worker_threads_that_ran_them():
    pool = JobPool(threads=2)
    try:
        world, sched = World(), Schedule(("update",), parallel=True)
        world.resources[JobPool] = pool
        barrier = threading.Barrier(2, timeout=10)  # both must run at once: on two threads
        sched.add(system(writes=[Transform], name="left")(lambda world, dt: barrier.wait()))
        sched.add(system(writes=[Velocity], name="right")(lambda world, dt: barrier.wait()))
        sched.timer = timer = Recorder()
        sched.run(world, 1 / 60)
        ran = {name: thread for name, thread, *_ in timer.runs}
        assert set(ran) == {"left", "right"}
        assert len(set(ran.values())) == 2 and any(t.startswith("ecs-job-") for t in ran.values())
    finally:
        pool.close()


def test_a_timed_pool_reports_each_job_by_name_on_its_thread():
    pool = JobPool(threads=2)
    try:
        pool.timer = timer = Recorder()
        barrier = threading.Barrier(2, timeout=10)
        pool.map(lambda chunk: barrier.wait(), ["a", "b"], ["chunk a", "chunk b"])
        assert sorted(name for name, _ in timer.jobs) == ["chunk a", "chunk b"]
        assert any(thread.startswith("ecs-job-") for _, thread in timer.jobs)
        pool.timer = None
        timer.jobs.clear()
        pool.map(lambda chunk: barrier.wait(), ["a", "b"])
        assert timer.jobs == []
    finally:
        pool.close()


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


class Sampler:
    cores = 2

    def sample(self) -> ProcessSample:
        return ProcessSample(0.0, 0.0, 0)


def test_the_monitor_keeps_system_and_pass_means_over_its_window_without_the_warm_up():
    clock = Clock()
    perf = PerfMonitor(window_s=1.0, warmup_frames=2, clock=clock, sampler=Sampler())
    for k in range(12):
        clock.t += 0.01
        warm = k < 2
        systems = {"physics": 50.0 if warm else 2.0, "ai": 1.0}
        if k % 2:
            systems.pop("ai")  # skipped by its run condition this frame: 0 ms
        passes = [("shadow maps", 0.5), ("forward", 1.5)]
        perf.frame(1.0, 0.1, 2.0, 0.0, Timings(systems, {"physics": "ecs-job-1", "ai": "MainThread"}, passes))
    perf.frame(1.0, 0.1, 2.0, 0.0, None)  # an untimed frame adds no row
    found = {x.name: x for x in perf.system_times()}
    assert [x.name for x in perf.system_times()] == ["physics", "ai"]  # slowest first
    assert found["physics"].mean == pytest.approx(2.0)  # the warm-up's 50 ms left out
    assert found["ai"].mean == pytest.approx(0.5)
    assert perf.system_threads["physics"] == "ecs-job-1"
    assert [(x.name, x.mean) for x in perf.gpu_pass_times()] == [("forward", 1.5), ("shadow maps", 0.5)]
    assert "systems physics 2.000, ai 0.500 ms" in perf.summary_line()
    clock.t += 5.0  # past the window: nothing timed in it
    perf.frame(1.0, 0.1, 2.0, 0.0, None)
    assert perf.system_times() == []


def test_the_perf_log_gives_timings_per_frame_and_summarised(tmp_path):
    path = tmp_path / "perf.json"
    perf = PerfMonitor(log=str(path), warmup_frames=1, sampler=Sampler())
    for k in range(4):
        timings = None if k == 2 else Timings({"move": 1.0 + k}, {"move": "MainThread"}, [("forward", 0.25)])
        perf.frame(1.0, 0.1, 2.0, 0.0, timings)
    perf.write_json(meta={})
    doc = json.loads(path.read_text())
    assert [f.get("systems_ms") for f in doc["frames"]] == [{"move": 1.0}, {"move": 2.0}, None, {"move": 4.0}]
    assert doc["frames"][0]["gpu_passes_ms"] == {"forward": 0.25}
    assert doc["systems"]["move"]["mean"] == pytest.approx(3.0)  # frames 1 and 3: warm-up and untimed out


def gpu_frame(start: int, ms: float, passes, submitted: int, done: int) -> GpuFrame:
    return GpuFrame(ms, start, passes, submitted, done)


def test_the_trace_keeps_the_last_frames_and_says_how_many_it_left_out(tmp_path):
    trace = TraceRecorder(tmp_path / "t.json", max_frames=3)
    t = trace.origin_ns
    for k in range(5):
        trace.span("system", f"system {k}", t + 10, t + 20)
        trace.frame(k, t, t + 100, None)
        t += 1000
    doc = trace.document()
    names = [e["name"] for e in doc["traceEvents"] if e.get("ph") == "X"]
    assert names == ["frame 2", "system 2", "frame 3", "system 3", "frame 4", "system 4"]
    assert doc["otherData"]["frames_left_out"] == 2 and doc["otherData"]["frames_in_file"] == 3
    notes = [e for e in doc["traceEvents"] if e.get("ph") == "i"]
    assert len(notes) == 1 and notes[0]["name"].startswith("2 earlier frames left out")
    trace.write()
    assert json.loads((tmp_path / "t.json").read_text())["otherData"]["frames_recorded"] == 5


def test_gpu_frames_are_placed_between_their_submit_and_their_fence():
    # a device clock 1 s behind the CPU's: each frame ran between submit and fence
    lag = 1_000_000_000
    gpus = [
        gpu_frame(10_000 - lag, 0.002, [("forward", 0.002)], 9_000, 13_000),
        gpu_frame(20_000 - lag, 0.001, [("forward", 0.001)], 19_500, 22_000),
    ]
    offset, uncertainty = gpu_clock(gpus)
    assert offset == 19_500 - (20_000 - lag) and offset <= lag
    assert offset + uncertainty == pytest.approx(22_000 - (20_000 - lag + 1_000))
    for g in gpus:
        assert g.submitted_ns <= g.start_ns + offset
        assert g.start_ns + offset + g.ms * 1e6 <= g.done_ns


def test_the_trace_puts_gpu_passes_on_a_gpu_track_inside_their_frame(tmp_path):
    trace = TraceRecorder(tmp_path / "t.json")
    t0 = trace.origin_ns
    trace.frame(0, t0, t0 + 50_000, None)
    gpu = gpu_frame(5_000, 0.03, [("shadow maps", 0.01), ("forward", 0.02)], t0 + 40_000, t0 + 120_000)
    trace.frame(1, t0 + 60_000, t0 + 130_000, gpu)
    doc = trace.document()
    track = [e for e in doc["traceEvents"] if e.get("pid") == 2 and e.get("ph") == "X"]
    assert [e["name"] for e in track] == ["GPU: frame 0", "shadow maps", "forward"]
    frame, *passes = track
    assert frame["args"]["submitted by"] == "frame 0"
    assert sum(p["dur"] for p in passes) == pytest.approx(frame["dur"])
    assert passes[1]["ts"] == pytest.approx(passes[0]["ts"] + passes[0]["dur"])
    assert frame["ts"] >= 40.0  # not before its submit (us from the recorder's start)
    stamps = [e["ts"] for e in doc["traceEvents"] if "ts" in e]
    assert stamps == sorted(stamps)
    assert np.isfinite(doc["otherData"]["gpu_clock"]["uncertainty_us"])
