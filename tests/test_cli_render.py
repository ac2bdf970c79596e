"""The demo command: headless runs, fallback without a display, and one clear line for every
bad input (exit 2, no traceback unless --debug)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image


def cli(*args, env=None, cwd=None):
    full_env = dict(os.environ, **(env or {}))
    return subprocess.run(
        [sys.executable, "-m", "ecs_engine", "demo", *args],
        capture_output=True,
        text=True,
        timeout=300,
        env=full_env,
        cwd=cwd,
    )


def one_line_error(proc, *fragments):
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    for fragment in fragments:
        assert fragment in lines[0]


def test_headless_screenshot_with_validation(tmp_path):
    shot = tmp_path / "grid.png"
    proc = cli(
        "grid100",
        "--headless",
        "--frames",
        "3",
        "--width",
        "96",
        "--height",
        "64",
        "--screenshot",
        str(shot),
        "--validate",
    )
    assert proc.returncode == 0, proc.stderr
    assert "validation" not in proc.stderr
    img = np.asarray(Image.open(shot))
    assert img.shape == (64, 96, 3) and img.max() > 30


def test_without_a_display_it_says_so_and_renders_headless(tmp_path):
    env = {"DISPLAY": "", "WAYLAND_DISPLAY": ""}
    proc = cli("cube", "--frames", "2", "--width", "64", "--height", "48", env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "no display found" in proc.stdout
    assert (tmp_path / "cube.png").is_file()


BAD_FILES = {
    "points.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "only points/lines"),
    "lines.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n", "only points/lines"),
    "empty.obj": ("# nothing here\n", "no vertices or faces"),
    "nan.obj": ("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "NaN"),
    "inf.obj": ("v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "infinite"),
    "range.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "refers to vertex 9"),
    "garbage.stl": ("this is not an stl file at all", ""),
    "notamesh.glb": ("hello", ""),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_model_files_give_one_line_naming_the_file(name, tmp_path):
    text, fragment = BAD_FILES[name]
    path = tmp_path / name
    path.write_text(text)
    proc = cli("model", str(path), "--headless")
    one_line_error(proc, str(path), fragment)


def test_missing_model_file_and_debug_traceback(tmp_path):
    missing = tmp_path / "nope.obj"
    one_line_error(cli("model", str(missing), "--headless"), str(missing))
    proc = cli("model", str(missing), "--headless", "--debug")
    assert proc.returncode != 0 and "Traceback" in proc.stderr


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["cube", "--width", "0", "--headless"], "above 0"),
        (["cube", "--frames", "-2", "--headless"], "above 0"),
        (["cube", "extra.obj", "--headless"], "a path goes with the model scene"),
        (["cube", "--present", "sometimes"], "invalid choice"),
    ],
)
def test_bad_flags(args, fragment):
    proc = cli(*args)
    one_line_error(proc, fragment)  # argparse's too: one line, not the usage text


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["cube", "--entities", "50", "--headless"], "--entities sizes the scaling and motion scenes"),
        (["cube", "--headless", "--present", "mailbox"], "a --headless run has no window"),
        (["cube", "--headless", "--mode", "indirect", "--recorder", "python"], "--recorder does not apply"),
        (["cube", "--headless", "--no-shadow-denoise"], "--no-shadow-denoise applies to --shadows raytraced"),
        (["cube", "--headless", "--culling", "frustum", "--no-culling"], "--no-culling: not allowed with argument"),
    ],
)
def test_a_flag_that_would_change_nothing_is_refused(args, fragment):
    one_line_error(cli(*args), fragment)


@pytest.mark.parametrize("name", ["out.txt", "out", "shot.PNG.jpg"])
def test_a_screenshot_name_that_is_not_a_png_is_refused_before_the_run(tmp_path, name):
    proc = cli("cube", "--headless", "--screenshot", str(tmp_path / name), "--width", "32", "--height", "24")
    one_line_error(proc, f"--screenshot {tmp_path / name}: screenshots are written as PNG", "ending in .png")
    assert "headless" not in proc.stdout  # refused before the scene started


def test_argparse_errors_point_to_help():
    one_line_error(cli("cube", "--width", "x"), "argument --width", "(see ecs-engine demo --help)")


def test_the_motion_demo_refuses_the_render_flags_it_cannot_use():
    one_line_error(
        cli("motion", "--screenshot", "m.png", "--mode", "indirect"),
        "motion is a text-mode ECS scene",
        "--screenshot, --mode do not apply",
    )
    proc = cli("motion", "--entities", "300", "--frames", "2", "--threads", "2")
    assert proc.returncode == 0 and "2 threads" in proc.stdout, proc.stderr


def test_screenshot_into_a_missing_folder(tmp_path):
    target = tmp_path / "no" / "such" / "dir.png"
    one_line_error(
        cli("cube", "--headless", "--screenshot", str(target), "--width", "32", "--height", "24"), "does not exist"
    )


def test_no_vulkan_loader_names_the_install_command(tmp_path):
    """The binding raises OSError at import when libvulkan.so.1 is missing; fake exactly that."""
    fake = tmp_path / "vulkan"
    fake.mkdir()
    (fake / "__init__.py").write_text("raise OSError('Cannot find Vulkan SDK version.')\n")
    # in front of the rest of the path (where the engine may be installed, as on the GPU host)
    proc = cli(
        "cube",
        "--headless",
        env={"PYTHONPATH": os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))},
    )
    one_line_error(proc, "no Vulkan loader", "apt-get install -y libvulkan1")


def test_no_vulkan_device_names_the_driver_package(tmp_path):
    icd = tmp_path / "none.json"
    icd.write_text(
        json.dumps(
            {
                "file_format_version": "1.0.0",
                "ICD": {"library_path": "/nonexistent/libnothing.so", "api_version": "1.3.0"},
            }
        )
    )
    proc = cli("cube", "--headless", env={"VK_ICD_FILENAMES": str(icd), "VK_DRIVER_FILES": str(icd)})
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "mesa-vulkan-drivers" in proc.stderr


def test_device_choice_by_name():
    proc = cli("cube", "--headless", env={"ECS_ENGINE_DEVICE": "no-such-gpu"})
    one_line_error(proc, "ECS_ENGINE_DEVICE='no-such-gpu'", "devices present")


def test_native_recorder_without_numba_is_a_clear_error():
    proc = cli("cube", "--headless", "--recorder", "native", env={"ECS_ENGINE_NO_NUMBA": "1"})
    one_line_error(proc, "native recorder needs numba", "--recorder python")


def editor_cli(*args, env=None, cwd=None):
    full_env = dict(os.environ, **(env or {}))
    return subprocess.run(
        [sys.executable, "-m", "ecs_engine", "editor", *args],
        capture_output=True,
        text=True,
        timeout=300,
        env=full_env,
        cwd=cwd,
    )


def test_editor_headless_draws_the_ui_and_writes_perf_json(tmp_path):
    import json

    shot, perf = tmp_path / "ed.png", tmp_path / "perf.json"
    proc = editor_cli(
        "grid100",
        "cube",
        "--headless",
        "--frames",
        "4",
        "--width",
        "480",
        "--height",
        "320",
        "--screenshot",
        str(shot),
        "--perf-json",
        str(perf),
        "--validate",
    )
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(perf.read_text())
    assert len(doc["frames"]) == 4 and doc["meta"]["scene"] == "grid100" and doc["meta"]["editor"] is True
    assert all(f["cpu_ms"] > 0 for f in doc["frames"]) and doc["psutil"]
    assert np.asarray(Image.open(shot)).shape == (320, 480, 3)


def test_editor_without_a_display_draws_the_editor_headless(tmp_path):
    """`make demo` with no display: the image is the editor the user asked for (its menu bar
    across the top), not the scene alone."""
    env = {"DISPLAY": "", "WAYLAND_DISPLAY": ""}
    proc = editor_cli("--frames", "2", "--width", "320", "--height", "200", env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "no display found: drawing the editor and its scene headless for 2 frames" in proc.stdout
    assert f"last frame saved to {tmp_path / 'grid100.png'}" in proc.stdout  # where, as a full path
    image = np.asarray(Image.open(tmp_path / "grid100.png"))
    menu_bar = image[4:14, 60:-2]  # right of "File", inside the window's border
    assert (menu_bar == (36, 36, 36)).all()  # ImGui's menu bar colour, edge to edge
    again = editor_cli("--frames", "1", "--width", "64", "--height", "48", env=env, cwd=tmp_path)
    assert again.returncode == 0 and "(replacing the file there)" in again.stdout  # says it overwrites


def test_perf_json_into_a_missing_folder_fails_before_running(tmp_path):
    target = tmp_path / "missing" / "perf.json"
    proc = cli("cube", "--headless", "--perf-json", str(target), "--width", "32", "--height", "24")
    one_line_error(proc, str(target))
    assert "headless" not in proc.stdout  # refused before the scene started


def test_editor_rejects_unknown_scenes():
    proc = editor_cli("motion", "--headless")
    assert proc.returncode == 2 and "invalid choice" in proc.stderr


def test_a_folder_as_screenshot_is_refused_before_the_run(tmp_path):
    proc = cli("cube", "--headless", "--screenshot", str(tmp_path), "--width", "32", "--height", "24")
    one_line_error(proc, f"{tmp_path}: is a directory, not a file to write the screenshot to")


@pytest.mark.parametrize(
    "args, words",
    [
        (["scaling", "--entities", str(10**12)], "needs about"),
        (["scaling", "--threads", "100000"], "--threads 100000: choose 1 to"),
    ],
)
def test_impossible_sizes_are_refused_at_once(args, words):
    import time

    start = time.perf_counter()
    proc = cli(*args, "--headless")
    one_line_error(proc, words)
    assert time.perf_counter() - start < 20  # refused before anything is allocated or started


def test_one_failing_output_does_not_lose_the_other(tmp_path, monkeypatch):
    import json

    import ecs_engine.app.loop as loop
    from ecs_engine.app.settings import RunOptions
    from ecs_engine.errors import UsageError

    def broken(pixels, path):
        raise UsageError(f"cannot write {path}: disk full")

    monkeypatch.setattr(loop, "save_png", broken)
    perf = tmp_path / "perf.json"
    with pytest.raises(UsageError, match="disk full"):
        loop.run(
            RunOptions(
                scene="cube",
                width=32,
                height=24,
                frames=2,
                quiet=True,
                screenshot=str(tmp_path / "x.png"),
                perf_json=str(perf),
            )
        )
    assert len(json.loads(perf.read_text())["frames"]) == 2  # the log was written all the same


def test_lights_demo_flags(tmp_path):
    shot = tmp_path / "lights.png"
    proc = cli(
        "lights", "--lights", "100", "--light-culling", "clustered", "--headless", "--frames", "2",
        "--width", "96", "--height", "64", "--validate", "--screenshot", str(shot),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "101 lights" in proc.stdout and shot.exists()
    one_line_error(cli("cube", "--lights", "10", "--headless"), "--lights", "cube")
    one_line_error(cli("lights", "--lights", "-1", "--headless"), "--lights -1")


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_a_windowed_screenshot_says_where_it_went(tmp_path):
    shot = tmp_path / "window.png"
    proc = cli("cube", "--frames", "2", "--width", "64", "--height", "48", "--screenshot", str(shot))
    assert proc.returncode == 0, proc.stderr
    assert f"wrote {shot}" in proc.stdout.splitlines()
    assert np.asarray(Image.open(shot)).shape[2] == 3


def test_outputs_never_replace_a_file_of_another_kind_nor_an_input(tmp_path):
    """--record-input over a scene, the input script as its own recording, --perf-json over notes:
    one line, exit 2, before the first frame, the file as it was; --force lets a kind be replaced."""
    scene, script, notes = tmp_path / "level.scene", tmp_path / "s.txt", tmp_path / "notes.txt"
    scene.write_bytes(b"PK\x03\x04 a saved scene")
    script.write_text("10 down w\n20 up w\n")
    notes.write_text("my notes\n")
    small = ("--width", "32", "--height", "24", "--frames", "2")
    for args, words in (
        (["--record-input", str(scene)], ("--record-input", "not an input script", "--force")),
        (["--input-script", str(script), "--record-input", str(script)], ("is also the --input-script",)),
        (["--perf-json", str(notes)], ("--perf-json", "not a --perf-json log")),
        (["--screenshot", str(notes.with_suffix(".png")), "--perf-json", str(notes.with_suffix(".png"))], ("is also",)),
    ):
        proc = cli("cube", "--headless", *small, *args)
        one_line_error(proc, *words)
        assert "headless" not in proc.stdout  # refused before the scene started
    assert scene.read_bytes() == b"PK\x03\x04 a saved scene" and script.read_text() == "10 down w\n20 up w\n"
    assert notes.read_text() == "my notes\n"
    proc = cli("cube", "--headless", *small, "--perf-json", str(notes), "--force")
    assert proc.returncode == 0 and json.loads(notes.read_text())["meta"]["frames"] == 2, proc.stderr


@pytest.mark.skipif(not os.path.isdir("/sys"), reason="uses /sys, where no one may create a file")
def test_an_output_where_nothing_can_be_written_is_refused_before_the_run():
    one_line_error(cli("cube", "--headless", "--record-input", "/sys/input.txt"), "/sys/input.txt", "cannot write")


def test_ctrl_c_after_some_frames_writes_the_perf_log_of_the_frames_run(tmp_path):
    import signal

    perf = tmp_path / "perf.json"
    proc = subprocess.Popen(
        [sys.executable, "-m", "ecs_engine", "demo", "cube", "--headless", "--frames", "100000"]
        + ["--width", "32", "--height", "24", "--perf-json", str(perf)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        seen = [proc.stdout.readline() for _ in range(3)]  # the run's first line, then two perf summaries
        assert seen[-1].startswith("fps"), seen
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert err.splitlines() == ["ecs-engine: interrupted"]
    doc = json.loads(perf.read_text())
    assert len(doc["frames"]) >= 2 and doc["meta"]["frames"] == len(doc["frames"])
    assert f"wrote {perf}" in out


def test_a_scene_file_without_a_camera_is_named(tmp_path, capsys):
    from ecs_engine import World
    from ecs_engine.app.cli import main
    from ecs_engine.components import Transform
    from ecs_engine.ecs.scene_file import save_world

    world = World()
    world.spawn(Transform())
    path = tmp_path / "empty.scene"
    save_world(world, path)
    assert main(["editor", str(path), "--headless", "--frames", "1", "--width", "32", "--height", "24"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"ecs-engine: error: scene file {path}: no camera") and len(err.splitlines()) == 1
