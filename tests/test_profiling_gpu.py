"""Profiling a real run (lavapipe, validation on): `--trace` writes a Chrome trace with the
frames, the systems, the recording jobs on worker threads and the GPU passes; the passes' times
are positive and add up to the frame's GPU time; the editor's Perf window lists systems and
passes; a bad trace path is refused before the first frame."""

from __future__ import annotations

import json
from collections import defaultdict

import pytest

from ecs_engine.app import cli
from ecs_engine.app.loop import run
from ecs_engine.app.settings import RunOptions


def tiny(tmp_path, **kw) -> RunOptions:
    kw = {"frames": 8, "width": 96, "height": 64, **kw}
    return RunOptions(scene="grid100", validate=True, quiet=True, threads=2, **kw)


def test_a_trace_has_frames_systems_worker_jobs_and_gpu_passes(tmp_path):
    path = tmp_path / "run.json"
    # 10 rows a recording job: grid100's 100 cubes are ten jobs, spread over the worker
    result = run(tiny(tmp_path, trace=str(path), chunk_rows=10))
    assert result.validation_messages == []
    doc = json.loads(path.read_text())
    events = doc["traceEvents"]
    assert doc["otherData"]["frames_in_file"] == 8 and doc["otherData"]["frames_left_out"] == 0
    threads = {e["tid"]: e["args"]["name"] for e in events if e["name"] == "thread_name" and e["pid"] == 1}
    slices = [e for e in events if e["ph"] == "X"]
    by_cat = defaultdict(list)
    for e in slices:
        by_cat[e["cat"]].append(e)
    assert len(by_cat["frame"]) == 8
    assert {"transform", "orbit"} <= {e["name"] for e in by_cat["system"]}
    worker_jobs = [e for e in by_cat["job"] if threads[e["tid"]].startswith("ecs-job-")]
    assert worker_jobs and all(e["name"].startswith("rows ") for e in worker_jobs)
    stamps = [e["ts"] for e in events if "ts" in e]
    assert stamps == sorted(stamps)  # the file's order is its timeline's
    # each system and job lies inside a frame on the CPU's timeline
    frames = sorted((e["ts"], e["ts"] + e["dur"]) for e in by_cat["frame"])
    for e in by_cat["system"] + by_cat["job"]:
        assert any(a <= e["ts"] and e["ts"] + e["dur"] <= b + 1e-3 for a, b in frames), e
    # the GPU track: a slice per frame whose timestamps came back, its passes inside it
    gpu_frames = by_cat["gpu"]
    assert len(gpu_frames) >= 5 and all(e["pid"] == 2 for e in gpu_frames)
    passes = by_cat["gpu pass"]
    assert "forward" in {e["name"] for e in passes}  # billboards included: one rendering of secondaries
    for frame in gpu_frames:
        inside = [p for p in passes if frame["ts"] <= p["ts"] < frame["ts"] + frame["dur"]]
        assert inside and all(p["dur"] > 0 for p in inside)
        total = sum(p["dur"] for p in inside)
        assert 0.5 * frame["dur"] <= total <= frame["dur"] + 1e-3  # the passes are most of the frame
    assert doc["otherData"]["gpu_clock"]["uncertainty_us"] >= 0


def test_the_editors_perf_window_lists_systems_and_gpu_passes(tmp_path, monkeypatch):
    pytest.importorskip("imgui_bundle")
    from ecs_engine.app import imgui_session, perf_overlay

    made = imgui_session.ImGuiSession.__init__

    def every_frame(self, *args, **kwargs):  # a fast GPU runs the 9 frames within one 1/120 s rebuild
        made(self, *args, **kwargs)
        self.min_interval_s = 0.0

    monkeypatch.setattr(imgui_session.ImGuiSession, "__init__", every_frame)
    monkeypatch.setattr(perf_overlay, "REFRESH_S", 0.0)  # and the lists refreshed every frame too
    result = run(tiny(tmp_path, editor=True, frames=9, width=1024, height=720))
    assert result.validation_messages == []
    overlay = result.editor.overlay
    assert overlay.visible  # drawn: so the frames were timed
    systems = [name for name, _, _ in overlay.systems]
    assert {"transform", "orbit"} <= set(systems)
    means = [float(ms) for _, ms, _ in overlay.systems]
    assert means == sorted(means, reverse=True)  # slowest first
    assert {thread for _, _, thread in overlay.systems} == {"main"}
    passes = dict(overlay.passes)
    assert {"forward", "imgui"} <= set(passes) and all(float(ms) > 0 for ms in passes.values())
    # the warm-up frames are left out: only the frames after it are in the window
    assert len(result.perf.systems.window(result.perf._last_t)) == len(overlay.systems)


def test_a_trace_path_that_cannot_be_written_is_refused_before_the_first_frame(tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text('{"not": "a trace"}')
    missing = tmp_path / "no such folder" / "t.json"
    base = ["demo", "cube", "--headless", "--frames", "2", "--width", "32", "--height", "32"]
    assert cli.main([*base, "--trace", str(missing)]) == 2
    out, err = capsys.readouterr()
    assert f"--trace {missing}" in err and "does not exist" in err
    assert err.count("\n") == 1 and "Traceback" not in err and "frames" not in out  # refused before a frame ran
    assert cli.main([*base, "--trace", str(scene)]) == 2  # another kind of file: only with --force
    assert scene.read_text() == '{"not": "a trace"}'


def test_ctrl_c_writes_the_trace_of_the_frames_run(tmp_path, monkeypatch):
    from ecs_engine.app.session import Session

    done = Session.frame_done
    calls = []

    def interrupted(self):  # Ctrl-C lands during the fourth frame
        calls.append(1)
        if len(calls) == 4:
            raise KeyboardInterrupt
        done(self)

    monkeypatch.setattr(Session, "frame_done", interrupted)
    path = tmp_path / "t.json"
    with pytest.raises(KeyboardInterrupt):
        run(tiny(tmp_path, trace=str(path), frames=100))
    doc = json.loads(path.read_text())
    assert doc["otherData"]["frames_recorded"] == 3
    assert [e["name"] for e in doc["traceEvents"] if e.get("cat") == "frame"] == ["frame 0", "frame 1", "frame 2"]
