"""Input scripts drive the editor's own UI (issue 33): headless editor runs whose `--input-script`
clicks an entity in the scene (it is selected), presses the gizmo's key (its mode changes), clicks
a button and a menu, types a path into the Open dialog with a shortcut and Enter (the scene
opens), and quits with Esc before --frames; Esc in the dialog closes the dialog, not the editor."""

from __future__ import annotations

import os
from typing import Any

import pytest

pytest.importorskip("imgui_bundle")

from test_editor_files import Meshes

from ecs_engine.app.editor_session import EditorSession
from ecs_engine.app.loop import run
from ecs_engine.app.session import Session
from ecs_engine.app.settings import RunOptions
from ecs_engine.components import Mesh

W, H = 960, 540  # the narrow layout: the scene in the middle, 360 pixels wide


class Watched(EditorSession):
    """The run's editor, noting after each UI built what a script could have changed."""

    def __init__(self, session: Session, window: Any = None) -> None:
        super().__init__(session, ("cube",), 2, window, max_ui_hz=None)
        self.session = session
        self.seen: list[dict[str, Any]] = []

    def build(self, world, stats, perf, dt, width, height) -> None:
        super().build(world, stats, perf, dt, width, height)
        e = self.editor
        self.seen.append(
            {
                "selected": e.selected,
                "picked": e.picked,
                "gizmo": e.gizmo.operation,
                "dialog": e.files.dialog,
                "path": e.files.path,
                "entities": len(world),
                "scene": self.session.scene,
            }
        )


def editor_run(tmp_path, script: str, frames: int, window: Any = None) -> tuple[Any, Watched, Session]:
    """A headless run, or in a window (`window`: True, or its on_frame hook)."""
    path = tmp_path / "script.txt"
    path.write_text(script)
    made: list[Any] = []

    def session(options: RunOptions, source: Any) -> Session:
        made.append(Session(options, source))
        return made[-1]

    def ui(session: Session, window: Any) -> Watched:
        made.append(Watched(session, window))
        return made[-1]

    options = RunOptions(
        scene="cube", width=W, height=H, frames=frames, validate=True, quiet=True, editor=True, input_script=str(path)
    )
    source = None
    if window:
        from dataclasses import replace

        from ecs_engine.app.window import WindowSource, open_glfw

        glfw = open_glfw()
        assert glfw is not None
        hook = window if callable(window) else None
        options, source = replace(options, headless=False), WindowSource(glfw, hook)
    result = run(options, source, make_session=session, ui=ui)
    assert result.validation_messages == []
    return result, made[1], made[0]


def centre(rect) -> tuple[float, float]:
    return ((rect[0] + rect[2]) / 2, (rect[1] + rect[3]) / 2)


def click(frame: int, at: tuple[float, float]) -> str:
    return f"{frame} move {at[0]} {at[1]}\n{frame + 1} down mouse_left\n{frame + 2} up mouse_left\n"


@pytest.fixture
def layout(tmp_path_factory, config_home):
    """Where the editor's widgets are at W x H (the default layout depends on the size alone)."""
    _, editor, _ = editor_run(tmp_path_factory.mktemp("probe"), "", 3)
    e = editor.editor
    return {"central": e.dock.central, "add cube": e.rects["add cube"], "File": e.files.rects["File"]}


def saved_cube(tmp_path) -> str:
    from ecs_engine import World
    from ecs_engine.demos.cube import build
    from ecs_engine.ecs.scene_file import save_world
    from ecs_engine.render.assets.scene_assets import scene_codecs

    world, meshes = World(), Meshes()
    build(world, meshes.add)
    path = tmp_path / "saved.scene"
    save_world(world, path, resources=scene_codecs(meshes))
    return str(path)


def test_a_script_clicks_picks_presses_keys_opens_the_file_menu_types_and_quits(tmp_path, layout):
    scene_file = saved_cube(tmp_path)
    x0, _, _, y1 = layout["File"]
    open_item = (x0 + 12, y1 + 12)  # the menu's first item, "Open...", under "File"
    script = (
        click(3, centre(layout["central"]))  # the cube, in the middle of the scene
        + "6 down e\n7 up e\n"  # the gizmo rotates
        + click(8, centre(layout["add cube"]))
        + click(11, centre(layout["File"]))
        + click(14, open_item)
        + "17 down left_control\n17 down a\n18 up a\n18 up left_control\n"  # select the path field's text
        + f'19 text "{scene_file}"\n20 down enter\n21 up enter\n'
        + "24 down escape\n25 up escape\n"
    )
    result, editor, session = editor_run(tmp_path, script, frames=60)
    seen = editor.seen
    cube = seen[2]["entities"]
    # frame 5: the click's release, picked in the scene
    assert seen[5]["selected"] is not None and seen[5]["picked"] == seen[5]["selected"]
    assert seen[2]["gizmo"] == "translate" and seen[7]["gizmo"] == "rotate"
    assert seen[10]["entities"] == cube + 1  # "add cube"
    assert seen[13]["dialog"] is None and seen[16]["dialog"] == "Open scene"
    assert seen[19]["path"] == scene_file  # Ctrl+A, then the typed text replaced it
    assert seen[22]["scene"] == scene_file and seen[22]["dialog"] is None
    assert editor.editor.files.status == f"opened {scene_file}"
    assert result.frames == 25 < 60  # Esc at frame 24 ended the run
    assert session.world.query(Mesh, write=()).count() == 1


def test_esc_in_the_open_dialog_closes_the_dialog_not_the_editor(tmp_path):
    script = "2 down left_control\n2 down o\n3 up o\n3 up left_control\n6 down escape\n7 up escape\n"
    result, editor, _ = editor_run(tmp_path, script, frames=10)
    seen = editor.seen
    assert seen[4]["dialog"] == "Open scene" and seen[7]["dialog"] is None
    assert result.frames == 10  # the run went on


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_in_a_window_the_scripts_pointer_clicks_not_the_real_one(tmp_path, layout):
    """ImGui's GLFW backend reports where the real cursor goes (here: moved over the settings
    panel between the script's move and its click): the script's pointer goes to ImGui after it,
    so the script's click lands where the script says."""
    from test_quit_key import x_display

    def real_pointer(frame: int, glfw: Any, window: Any) -> None:
        if frame in (2, 4):
            with x_display() as (x11, display):
                x11.XSetInputFocus(display, glfw.get_x11_window(window), 1, 0)
                x11.XWarpPointer(display, 0, glfw.get_x11_window(window), 0, 0, 0, 0, 20 + frame, 100)

    script = click(3, centre(layout["central"])) + "6 down r\n7 up r\n"
    result, editor, _ = editor_run(tmp_path, script, frames=10, window=real_pointer)
    seen = editor.seen
    assert seen[5]["selected"] is not None and seen[5]["picked"] == seen[5]["selected"]
    assert seen[7]["gizmo"] == "scale" and result.frames == 10


def test_a_headless_scripted_run_builds_the_ui_every_frame(tmp_path):
    """The UI's rate limit (wall clock) would put a script's frames into whichever UI frame the
    machine's speed gives; with a script the UI is built every frame, so a run replays the same
    on a 2-core box and on the GPU host."""
    path = tmp_path / "keys.txt"
    path.write_text("2 down e\n3 up e\n")
    options = RunOptions(scene="cube", width=320, height=240, frames=8, quiet=True, editor=True, input_script=str(path))
    result = run(options, max_ui_hz=0.5)  # at most one UI every 2 s, were it not for the script
    assert result.editor.builds == 8 and result.editor.editor.gizmo.operation == "rotate"
