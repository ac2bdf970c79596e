"""Saving what you play: a game's systems save its world through SceneFiles (at the end of the
frame, with the frame's queued changes in), meshes by reference; the game's own components come
back under a stable name when that game loads the file; an App's world reopens in the editor;
a component no loader could find again is refused at save time, one line."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from PIL import Image
from test_app import cube_app, drawn
from test_play_file import main

GAME = '''
"""Rolls a ball; saves at step 2 (after spawning a marker in the same system); --load continues."""
import numpy as np
import pytest

from ecs_engine import App, Component, DefaultPlugins, Field, SceneFiles, Time
from ecs_engine.app.plugins import ScenePlugin
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.meshes import Meshes
from ecs_engine.render.assets.primitives import sphere_mesh


class Ball(Component):
    speed = Field(np.float64, default=1.0, finite=True)


class Marker(Component):
    step = Field(np.int64, default=0)


def setup(world, dt):
    ball = world.resources[Meshes].add(sphere_mesh(16, 8))
    world.spawn(Transform(), Mesh(handle=ball, material=2), Ball(speed=2.5))
    world.spawn(Transform(rotation=look_rotation((0.0, -1.0, -1.0))), DirectionalLight(illuminance=2.0))
    world.spawn(Transform(position=(0.0, 0.0, 4.0)), Camera())


def save(world, dt):
    steps = world.resources[Time].steps
    if steps == 2 and world.resources["save"]:
        world.spawn(Marker(step=steps))  # queued: the save must wait for it
        world.resources[SceneFiles].save(world.resources["save"])


def add_arguments(parser):
    parser.add_argument("--save")
    parser.add_argument("--load")


def build(app):
    if app.options.load:  # continue a saved game: its world instead of a new one
        app.add_plugins(DefaultPlugins.set(ScenePlugin(load=app.options.load)))
    else:
        app.add_plugins(DefaultPlugins)
        app.add_startup_systems(setup)
    app.insert_resource(app.options.save, key="save")
    app.add_systems("update", save)
    app.set_summary(
        lambda world: f"balls {world.query(Ball).count()} markers {world.query(Marker).count()} "
        f"meshes {len(world.resources[Meshes])} speeds {sorted(world.query(Ball).column(Ball.speed).tolist())}"
    )
'''

SMALL = ("--headless", "--width", "48", "--height", "32", "--threads", "1")


def test_a_game_saves_from_a_system_and_loads_back_in_that_game(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ball_saver.py").write_text(GAME)
    code, out, err = main(capsys, "play", "ball_saver.py", *SMALL, "--frames", "4", "--save", "saved.scene")
    assert code == 0, err
    assert "balls 1 markers 1 meshes 1" in out
    code, out, err = main(capsys, "play", "ball_saver.py", *SMALL, "--frames", "1", "--load", "saved.scene")
    assert code == 0, err
    # the saved ball (its speed, its sphere made again from the saved recipe) and the marker
    assert "balls 1 markers 1 meshes 1 speeds [2.5]" in out and "1 of 1 entities drawn" in out


def test_a_saved_app_world_reopens_in_the_editor(tmp_path, capsys):
    app = cube_app()
    app.run(frames=1, headless=True, threads=1)
    capsys.readouterr()
    app.world.save(tmp_path / "cube.scene")
    shot = tmp_path / "editor.png"
    argv = ["editor", str(tmp_path / "cube.scene"), "--headless", "--frames", "1", "--threads", "1"]
    code, out, err = main(capsys, *argv, "--width", "480", "--height", "320", "--screenshot", str(shot))
    assert code == 0, err
    assert "1 of 1 entities drawn" in out  # the cube, its mesh made again from the saved recipe
    assert drawn(np.asarray(Image.open(shot))) > 0.3


def test_a_script_saves_its_components_under_its_own_name_and_the_repl_is_refused(tmp_path):
    script = tmp_path / "stars.py"
    script.write_text(
        textwrap.dedent(
            """
            import json, sys, zipfile
            import numpy as np
            from ecs_engine import Component, Field, World

            class Star(Component):
                glow = Field(np.float32, default=1.0)

            world = World()
            world.spawn(Star(glow=2.0))
            world.save(sys.argv[1])
            print(json.loads(zipfile.ZipFile(sys.argv[1]).read("header.json"))["tables"][0]["components"])
            """
        )
    )
    run = subprocess.run([sys.executable, str(script), str(tmp_path / "s.scene")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "['stars.Star']"  # what `ecs-engine play stars.py` imports it as
    source = script.read_text().replace("sys.argv[1]", repr(str(tmp_path / "r.scene")))
    run = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True)
    assert run.returncode != 0 and not (tmp_path / "r.scene").exists()
    assert (
        "cannot save Star: it is defined in __main__ with no file (typed in the REPL or python -c); "
        "define it in a module or give it a scene_name"
    ) in run.stderr.strip().splitlines()[-1]


def test_meshes_load_a_model_file_and_save_it_by_reference_without_a_gpu(tmp_path):
    """Meshes.load in a simulation (MinimalPlugins: a CPU MeshList); the scene keeps the file's path."""
    from ecs_engine import App, MinimalPlugins, World
    from ecs_engine.components import Mesh, Transform
    from ecs_engine.errors import UsageError
    from ecs_engine.render.assets.meshes import Meshes

    model = tmp_path / "tri.obj"
    model.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    app = App(title="Models").add_plugins(MinimalPlugins)

    def setup(world, dt):
        world.spawn(Transform(), Mesh(handle=world.resources[Meshes].load(model)))

    app.add_startup_systems(setup)
    app.run(frames=1)
    assert app.world.resources[Meshes][0].positions.shape == (3, 3)
    app.world.save(tmp_path / "m.scene")
    again = World()
    again.resources[Meshes] = Meshes()
    World.load(tmp_path / "m.scene", into=again)
    assert again.resources[Meshes][0].source == {"file": str(model)}
    (tmp_path / "bad.obj").write_text("v 0 0\n")
    with pytest.raises(UsageError, match=r"bad\.obj"):
        Meshes().load(tmp_path / "bad.obj")
