"""`ecs-engine play GAME` and `ecs-engine editor GAME` on any game module (a file, a folder, a
module name, a known name), with the game's own options; every way a game file can be broken
is one line naming it, exit 2; `ecs-engine new` writes a game that runs; the tutorial's Catch
example plays headless and shows the game."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_app import drawn

from ecs_engine.app import cli

ROOT = Path(__file__).resolve().parent.parent

GAME = '''
"""A game written from the docs: components, a startup system, a camera, a light, a mesh, input."""
import numpy as np

from ecs_engine import App, Component, DefaultPlugins, Field
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.meshes import Meshes
from ecs_engine.render.assets.primitives import sphere_mesh
from ecs_engine.systems import InputState


class Ball(Component):
    speed = Field(np.float64, default=1.0, finite=True)


def setup(world, dt):
    ball = world.resources[Meshes].add(sphere_mesh(16, 8))
    world.spawn(Transform(), Mesh(handle=ball, material=2), Ball(speed=world.resources["speed"]))
    world.spawn(Transform(rotation=look_rotation((0.0, -1.0, -1.0))), DirectionalLight(illuminance=2.0))
    world.spawn(Transform(position=(0.0, 0.0, 3.0)), Camera())


def roll(world, dt):
    up = world.resources[InputState].down("up")
    for batch in world.query(Transform, Ball):
        batch[Transform].position[:, 1] += batch[Ball].speed * dt * (1.0 if up else 0.0)


def add_arguments(parser):
    parser.add_argument("--speed", type=float, default=1.0)


def build(app):
    app.title = "Ball game"
    app.add_plugins(DefaultPlugins)
    app.insert_resource(app.options.speed, key="speed")
    app.add_startup_systems(setup)
    app.add_systems("update", roll)
    app.set_summary(lambda world: f"ball at {world.query(Transform, Ball).column(Transform.position)[0, 1]:.3f}")
'''


def main(capsys, *argv: str) -> tuple[int, str, str]:
    """The CLI in this process: its exit status (argparse's SystemExit too), stdout, stderr."""
    try:
        code = cli.main(list(argv))
    except SystemExit as exit_:
        code = int(exit_.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


def test_a_game_file_plays_headless_with_its_own_options(tmp_path, capsys):
    game = tmp_path / "ball_game.py"
    game.write_text(GAME)
    script = tmp_path / "keys.txt"
    script.write_text("0 down up\n")
    shot = tmp_path / "ball.png"
    argv = ["play", str(game), "--headless", "--frames", "30", "--width", "64", "--height", "48", "--threads", "1"]
    code, out, err = main(capsys, *argv, "--speed", "2", "--input-script", str(script), "--screenshot", str(shot))
    assert code == 0, err
    assert out.startswith("ball_game: headless 64x48, 30 frames")
    assert "ball at 1.000" in out  # 30 frames of 1/60 s at speed 2, the key held
    assert drawn(np.asarray(Image.open(shot))) > 0.02
    code, _, err = main(capsys, "play", str(game), "--headless", "--speed", "fast")
    assert code == 2 and "argument --speed: invalid float value: 'fast'" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize(
    ("name", "source", "message"),
    [
        ("missing.py", None, "no game file {path}"),
        ("broken.py", "def build(app)\n    pass\n", "{path}:1: syntax error: expected ':'"),
        (
            "raising.py",
            "raise RuntimeError('no assets folder')\n",
            "{path}: importing it raised RuntimeError: no assets",
        ),
        ("empty.py", "x = 1\n", "{path}: has no build(app) function"),
        ("failing.py", "def build(app):\n    app.add_systems('later', print)\n", "unknown stage 'later'"),
        ("bug.py", "def build(app):\n    1 / 0\n", "{path}: build(app) raised ZeroDivisionError: division by zero"),
        ("json.py", "def build(app):\n    pass\n", "{path}: its name 'json' is already a module's"),
    ],
)
def test_a_broken_game_file_is_one_line_naming_it(tmp_path, capsys, name, source, message):
    path = tmp_path / name
    if source is not None:
        path.write_text(source)
    code, out, err = main(capsys, "play", str(path), "--headless")
    assert code == 2 and out == "", (out, err)
    assert err.startswith(f"ecs-engine: error: {message.format(path=path)}")
    assert len(err.strip().splitlines()) == 1
    code, _, debug = main(capsys, "play", str(path), "--headless", "--debug")
    assert code == 2 and "Traceback" in debug and debug.strip().splitlines()[-1] == err.strip()
    cause = {"broken.py": "SyntaxError", "raising.py": "RuntimeError", "bug.py": "ZeroDivisionError"}.get(name)
    assert cause is None or f"{cause}:" in debug  # the game's own error, where it came from


def test_unknown_names_and_module_names(capsys):
    code, _, err = main(capsys, "play", "chess", "--headless")
    assert code == 2 and "invalid choice: 'chess'" in err
    code, _, err = main(capsys, "play", "json", "--headless")  # a module, but no build
    assert (
        code == 2 and err.strip() == "ecs-engine: error: json: has no build(app) function (what a game module defines)"
    )
    code, _, err = main(capsys, "play", "ecs_engine.demos.cube", "--headless")  # a demo scene's build
    assert code == 2 and err.strip() == (
        "ecs-engine: error: ecs_engine.demos.cube: its build(world, add_mesh, path) is not a game's build(app), "
        "which takes the App"
    )


def test_a_known_game_by_module_name_takes_its_options(capsys):
    argv = ["play", "ecs_engine.demos.asteroids", "--headless", "--autoplay", "--frames", "2", "--threads", "1"]
    code, out, err = main(capsys, *argv, "--width", "48", "--height", "32", "--seed", "3")
    assert code == 0, err
    assert out.startswith("asteroids: headless 48x32, 2 frames") and "asteroids: score 0 at level 1" in out


def test_new_writes_a_starter_game_that_runs_and_refuses_an_existing_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, _ = main(capsys, "new", "rocket")
    assert code == 0 and out.strip() == "wrote rocket/game.py; play it with: ecs-engine play rocket"
    text = (tmp_path / "rocket" / "game.py").read_text()
    assert "def build(app):" in text and "App()" in text and len(text.splitlines()) < 70
    code, out, err = main(capsys, "play", "rocket/game.py", "--headless", "--frames", "60", "--screenshot", "x.png")
    assert code == 0, err
    assert drawn(np.asarray(Image.open(tmp_path / "x.png"))) > 0.05  # the cube
    code, _, err = main(capsys, "play", "rocket", "--headless", "--frames", "1", "--width", "32", "--height", "24")
    assert code == 0, err  # the folder names its game.py
    (tmp_path / "rocket" / "game.py").write_text("# mine\n")
    code, _, err = main(capsys, "new", "rocket")
    assert (
        code == 2
        and err.strip() == "ecs-engine: error: new: rocket exists already; choose another name (nothing was written)"
    )
    assert (tmp_path / "rocket" / "game.py").read_text() == "# mine\n"


def test_the_editor_opens_a_game_file(tmp_path, capsys):
    game = tmp_path / "ball_editor.py"
    game.write_text(GAME)
    shot = tmp_path / "editor.png"
    argv = ["editor", str(game), "--headless", "--frames", "2", "--width", "640", "--height", "400"]
    code, out, err = main(capsys, *argv, "--threads", "1", "--screenshot", str(shot), "--speed", "3")
    assert code == 0, err
    assert out.startswith("ball_editor: headless 640x400, 2 frames") and "ball at 0.000" in out
    assert drawn(np.asarray(Image.open(shot))) > 0.3  # the editor's panels


def test_the_catch_example_plays_headless_and_shows_the_game(tmp_path, capsys, monkeypatch):
    """The command docs/examples/catch.py gives, as a user runs it."""
    monkeypatch.chdir(tmp_path)
    example = str(ROOT / "docs" / "examples" / "catch.py")
    code, out, err = main(capsys, "play", example, "--headless", "--frames", "120", "--screenshot", "out.png")
    assert code == 0, err
    still = int(out.split("catch: ")[-1].split()[0])  # nobody moved the paddle: what falls on it
    pixels = np.asarray(Image.open(tmp_path / "out.png"))
    stars = (pixels[..., 0] > 200) & (pixels[..., 1] > 150) & (pixels[..., 2] < 150)  # gold
    paddle = (pixels[..., 2] > 180) & (pixels[..., 0] < 150)  # blue
    assert stars.sum() > 500 and paddle.sum() > 500
    code, out, err = main(capsys, "play", example, "--headless", "--frames", "120", "--autoplay", "--width", "320")
    assert code == 0, err
    assert int(out.split("catch: ")[-1].split()[0]) > still  # the bot catches more


def test_python_runs_a_game_file_as_a_script(tmp_path):
    """`python game.py` with App(...).run() in its main block: the same game, one process."""
    game = tmp_path / "scripted.py"
    game.write_text(
        GAME
        + textwrap.dedent(
            """
            if __name__ == "__main__":
                import argparse
                app = App(size=(48, 32))
                app.options = argparse.Namespace(speed=1.0)
                build(app)
                app.run(frames=3, headless=True, threads=1)
            """
        )
    )
    run = subprocess.run([sys.executable, str(game)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("scripted: headless 48x32, 3 frames") and "ball at 0.000" in run.stdout
