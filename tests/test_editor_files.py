"""The editor's File menu (app/editor_files.py): Ctrl+S on a demo scene asks for a path and
saves there; Ctrl+O opens a saved scene as the next scene, the edit made before saving included;
Save then writes to the file the scene came from; a bad file is refused with one line and the
scene in use stays; `ecs-engine editor FILE.scene` opens one and a missing one is one error."""

from __future__ import annotations

import numpy as np
import pytest
from test_editor_scene import key_chord

from ecs_engine.components import Transform
from ecs_engine.ecs.scene_file import load_world
from ecs_engine.render.assets.scene_assets import scene_codecs


class Meshes(list):
    """A session's mesh registry as the scene codecs see it, without the GPU."""

    def add(self, mesh):
        self.append(mesh)
        return len(self) - 1


def type_path(scene, path) -> None:
    """Replace the dialog's path field (it has the keyboard) with `path` and press Enter."""
    from imgui_bundle import imgui

    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.a)
    scene.io.add_input_characters_utf8(str(path))
    scene.frame()
    scene.io.add_key_event(imgui.Key.enter, True)
    scene.frame()
    scene.io.add_key_event(imgui.Key.enter, False)
    scene.frame()


def test_save_then_open_a_scene_through_the_menu_shortcuts(scene, tmp_path):
    from imgui_bundle import imgui

    editor, world = scene.session.editor, scene.state.world
    for _ in range(2):
        scene.frame()
    moved = int(world.query(Transform).entities()[7])
    world.set(moved, Transform, position=np.array([4.0, 5.0, 6.0]))
    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.s)  # grid100 came from no file: Save as
    assert editor.files.dialog == "Save scene as"
    type_path(scene, tmp_path / "level")  # .scene is added
    path = tmp_path / "level.scene"
    assert editor.files.dialog is None and not editor.files.failed, editor.files.status
    assert path.is_file() and editor.files.status == f"saved {len(world):,} entities to {path}"

    check, _ = load_world(path, type(world)(), resources=scene_codecs(Meshes()))
    assert len(check) == len(world)

    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.o)
    assert editor.files.dialog == "Open scene"
    type_path(scene, path)
    scene.frame()  # the loop applied the request between frames
    loaded = scene.state.world
    assert loaded is not world and scene.state.scene == str(path) == editor.settings.scene
    assert len(loaded) == len(world) and editor.files.status == f"opened {path}"
    found = [e for e in loaded.query(Transform).entities() if np.allclose(loaded.get(e, Transform).position, (4, 5, 6))]
    assert len(found) == 1

    # Save now writes to the file the scene came from, without asking
    loaded.destroy(found[0])
    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.s)
    assert editor.files.dialog is None and f"saved {len(loaded):,} entities to {path}" == editor.files.status
    again, _ = load_world(path, type(world)(), resources=scene_codecs(Meshes()))
    assert len(again) == len(world) - 1


def test_a_bad_scene_file_is_refused_and_the_scene_stays(scene, tmp_path):
    from imgui_bundle import imgui

    editor = scene.session.editor
    scene.frame()
    world = scene.state.world
    bad = tmp_path / "broken.scene"
    bad.write_bytes(b"PK\x03\x04 not really a zip")
    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.o)
    type_path(scene, bad)
    scene.frame()
    assert scene.state.world is world and scene.state.scene == "grid100"
    assert editor.files.failed and editor.files.status.startswith(f"scene file {bad}: ")
    # a path that is no scene file keeps the dialog open with the reason
    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.o)
    type_path(scene, tmp_path / "nothing.scene")
    assert editor.files.dialog == "Open scene" and editor.files.status == f"no scene file {tmp_path / 'nothing.scene'}"


@pytest.mark.parametrize("case", ["missing", "broken"])
def test_the_editor_command_refuses_a_bad_scene_file_in_one_line(tmp_path, case, capsys):
    from ecs_engine.app.cli import main

    path = tmp_path / "x.scene"
    if case == "broken":
        path.write_text("not a zip")
    try:
        code = main(["editor", str(path), "--headless", "--frames", "1", "--width", "64", "--height", "48"])
    except SystemExit as exit:  # argparse's own refusal (a missing file is a bad argument)
        code = exit.code
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "x.scene" in err and "Traceback" not in err


def test_the_editor_command_opens_a_saved_scene(tmp_path, capsys):
    from ecs_engine import World
    from ecs_engine.app.cli import main
    from ecs_engine.demos.cube import build
    from ecs_engine.ecs.scene_file import save_world

    world, meshes = World(), Meshes()
    build(world, meshes.add)
    path = tmp_path / "cube.scene"
    save_world(world, path, resources=scene_codecs(meshes))
    png = tmp_path / "out.png"
    code = main(
        [
            "editor",
            str(path),
            "--headless",
            "--frames",
            "2",
            "--width",
            "96",
            "--height",
            "64",
            "--screenshot",
            str(png),
        ]
    )
    assert code == 0, capsys.readouterr().err
    assert png.is_file()
