"""File > Open never ends the editor (issue 34 #3): a scene file that loads but cannot run (a
Parent pointing at itself or in a loop, a missing environment file, a Mesh.handle naming no
mesh) and a handful of broken files are each refused in one line naming the file, and the run
goes on with the scene that was open: the same world, drawn the same (its environment map and
meshes intact), headless and in a window (the acquired swapchain image given back)."""

from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("imgui_bundle")

from test_editor_files import Meshes

from ecs_engine import World
from ecs_engine.app.editor_session import EditorSession
from ecs_engine.app.loop import run
from ecs_engine.app.session import Session
from ecs_engine.app.settings import RunOptions
from ecs_engine.components import Camera, DirectionalLight, Environment, Mesh, Parent, Transform
from ecs_engine.ecs.scene_file import save_world
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.assets.scene_assets import scene_codecs

W, H = 800, 480  # the narrow layout: the scene in the middle, 200 pixels wide
FRAMES_PER_OPEN = 4  # the open is applied after its frame, the scene fails in the next


def still_scene(path: Path, broken: Any = None) -> str:
    """A scene file: a cube under a sun before a small sky (an environment map on the GPU), seen
    from a camera; nothing moves, so every frame draws the same. `broken(world, meshes)` spoils it."""
    world, meshes = World(), Meshes()
    cube = meshes.add(cube_mesh())
    world.spawn(Transform(), Mesh(handle=cube))
    world.spawn(Transform(position=np.array([2.0, 1.5, 3.0]), rotation=look_rotation((-2.0, -1.5, -3.0))), Camera())
    world.spawn(Transform(rotation=look_rotation((0.3, -1.0, -0.2))), DirectionalLight(illuminance=2.0))
    sky = np.zeros((8, 16, 3), np.float32)
    sky[:4] = (0.4, 0.6, 1.0)  # blue above, dark below
    world.resources[Environment] = Environment(sky)
    codecs = scene_codecs(meshes)
    if broken is not None:
        codecs = broken(world, meshes) or codecs
    save_world(world, path, resources=codecs)
    return str(path)


def parent_of_itself(world: World, meshes: Meshes) -> None:
    e = world.spawn(Transform())
    world.add(e, Parent(entity=e))


def parent_loop(world: World, meshes: Meshes) -> None:
    a = world.spawn(Transform())
    b = world.spawn(Transform(), Parent(entity=a))
    world.add(a, Parent(entity=b))


def missing_environment(world: World, meshes: Meshes) -> None:
    world.resources[Environment] = Environment(str(Path(os.devnull).parent / "no-such-sky.hdr"))


def handle_of_no_mesh(world: World, meshes: Meshes) -> list:
    world.spawn(Transform(), Mesh(handle=4_000_000_000))
    return [c for c in scene_codecs(meshes) if c.name != "meshes"]  # a file with no meshes at all


class Opener(EditorSession):
    """The run's editor; File > Open of `opens[frame]` at that frame (as the dialog's Open
    button does), noting what the run had after each UI built."""

    def __init__(self, session: Session, window: Any, opens: dict[int, str]) -> None:
        super().__init__(session, ("start",), 2, window, max_ui_hz=None)
        self.session, self.opens, self.frame = session, opens, 0
        self.seen: list[tuple[str, int, str, bool]] = []

    def build(self, world, stats, perf, dt, width, height) -> None:
        super().build(world, stats, perf, dt, width, height)
        files = self.editor.files
        self.seen.append((self.session.scene, id(world), files.status, files.failed))
        if self.frame in self.opens:
            files.open(self.editor, self.opens[self.frame])
        self.frame += 1


def editor_run(start: str, opens: dict[int, str], frames: int, tmp_path: Path, window: bool = False):
    made: list[Any] = []

    def session(options: RunOptions, source: Any) -> Session:
        made.append(Session(options, source))
        return made[-1]

    def ui(session: Session, win: Any) -> Opener:
        made.append(Opener(session, win, opens))
        return made[-1]

    png = tmp_path / f"last-{len(opens)}.png"
    options = RunOptions(
        scene=start, width=W, height=H, frames=frames, validate=True, quiet=True, editor=True, screenshot=str(png)
    )
    source = None
    if window:
        from dataclasses import replace

        from ecs_engine.app.window import WindowSource, open_glfw

        glfw = open_glfw()
        assert glfw is not None
        options, source = replace(options, headless=False), WindowSource(glfw)
    result = run(options, source, make_session=session, ui=ui)
    assert result.validation_messages == []
    return result, made[0], made[1]


def check_refused(seen, opens: dict[int, str], start: str) -> None:
    """After each open: the scene that was open, the same world, one line naming the file."""
    first = seen[0][1]
    for frame, path in opens.items():
        scene, world, status, failed = seen[frame + FRAMES_PER_OPEN - 1]
        assert scene == start and world == first, (path, status)
        assert failed and Path(path).name in status and "\n" not in status, status


def central(result, editor) -> np.ndarray:
    x0, y0, x1, y1 = (round(v) for v in editor.editor.dock.central)
    return result.pixels[y0:y1, x0:x1, :3]


def test_a_scene_that_loads_but_cannot_run_is_refused_and_the_old_one_stays(tmp_path):
    start = still_scene(tmp_path / "start.scene")
    bad = {
        "self": still_scene(tmp_path / "self.scene", parent_of_itself),
        "loop": still_scene(tmp_path / "loop.scene", parent_loop),
        "sky": still_scene(tmp_path / "sky.scene", missing_environment),
        "handle": still_scene(tmp_path / "handle.scene", handle_of_no_mesh),
    }
    opens = {2 + FRAMES_PER_OPEN * k: path for k, path in enumerate(bad.values())}
    frames = 2 + FRAMES_PER_OPEN * len(opens) + 2
    result, _, editor = editor_run(start, opens, frames, tmp_path)
    assert result.frames == frames  # the editor ran to the end
    check_refused(editor.seen, opens, start)
    statuses = [editor.seen[f + FRAMES_PER_OPEN - 1][2] for f in opens]
    assert "a parent chain loops" in statuses[0] and "a parent chain loops" in statuses[1]
    assert "no-such-sky.hdr" in statuses[2]
    assert "Mesh.handle 4000000000" in statuses[3]
    assert not set(bad.values()) & set(editor.editor.scenes)  # the switcher does not offer them
    # drawn as before any open: the same world, its sky map and cube still on the GPU
    plain, _, quiet = editor_run(start, {}, frames, tmp_path)
    assert np.abs(central(result, editor).astype(int) - central(plain, quiet)).max() <= 2


def spoiled(good: Path, where: Path, how: str) -> str:
    """`good` with one thing wrong, at `where`."""
    data = good.read_bytes()
    if how == "truncated":
        where.write_bytes(data[: len(data) // 2])
    elif how == "noise":
        where.write_bytes(np.random.default_rng(3).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    elif how == "empty":
        where.write_bytes(b"")
    elif how == "directory":
        where.mkdir()
    else:
        members = {}
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            for name in z.namelist():
                members[name] = z.read(name)
        header = json.loads(members["header.json"])
        if how == "header not json":
            members["header.json"] = b"{not json"
        elif how == "header of wrong types":
            header["entities"] = "many"
            members["header.json"] = json.dumps(header).encode()
        elif how == "unknown component":
            text = json.dumps(header).replace(".transform.Transform", ".transform.NoSuchComponent")
            members["header.json"] = text.encode()
        elif how == "array garbled":
            name = next(n for n in members if n.endswith(".npy"))
            members[name] = members[name][:20] + b"\xff" * 40
        with zipfile.ZipFile(where, "w") as z:
            for name, value in members.items():
                z.writestr(name, value)
    return str(where)


BROKEN = (
    "truncated",
    "noise",
    "empty",
    "directory",
    "header not json",
    "header of wrong types",
    "unknown component",
    "array garbled",
)


def no_camera(world: World, meshes: Meshes) -> None:
    world.destroy(int(world.query(Camera).entities()[0]))


def test_broken_scene_files_leave_the_editor_running_with_the_old_scene(tmp_path):
    start = still_scene(tmp_path / "start.scene")
    files = [spoiled(Path(start), tmp_path / f"{k}-{how.replace(' ', '-')}.scene", how) for k, how in enumerate(BROKEN)]
    files.append(still_scene(tmp_path / "no-camera.scene", no_camera))
    opens = {2 + FRAMES_PER_OPEN * k: path for k, path in enumerate(files)}
    frames = 2 + FRAMES_PER_OPEN * len(opens) + 1
    result, session, editor = editor_run(start, opens, frames, tmp_path)
    assert result.frames == frames
    check_refused(editor.seen, opens, start)
    assert session.scene == start and session.world.query(Mesh, write=()).count() == 1
    assert editor.editor.scenes == ("start",)  # no broken file is offered in the scene switcher


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_in_a_window_a_failed_scenes_frame_gives_its_image_back(tmp_path):
    """The frame that fails has acquired a swapchain image: it is given back (validation clean)
    and the window goes on drawing the old scene."""
    start = still_scene(tmp_path / "start.scene")
    opens = {
        2: still_scene(tmp_path / "loop.scene", parent_loop),  # fails in the systems
        2 + FRAMES_PER_OPEN: still_scene(tmp_path / "handle.scene", handle_of_no_mesh),  # in the renderer
    }
    frames = 2 + 2 * FRAMES_PER_OPEN + 3
    result, _, editor = editor_run(start, opens, frames, tmp_path, window=True)
    assert result.frames == frames and result.recreations >= 2  # a new swapchain took each image back
    check_refused(editor.seen, opens, start)


def test_failures_no_loader_foresaw_are_refused_too(tmp_path, monkeypatch):
    """Whatever a scene file's loading or first frames raise, not only the errors a user can
    cause: a loader's TypeError, a system's RuntimeError, an error drawing the UI for the new
    world (ImGui is left mid-frame: its windows are ended so the next frame can begin)."""
    from ecs_engine.app import editor as editor_module
    from ecs_engine.app import session as session_module
    from ecs_engine.ecs.schedule import System

    start = still_scene(tmp_path / "start.scene")
    names = ("typeerror", "system", "ui")
    paths = {name: still_scene(tmp_path / f"{name}.scene") for name in names}
    load = session_module.load_world

    def loader(path, world, **kw):
        if Path(path).stem == "typeerror":
            raise TypeError("unsupported operand type(s) for +: 'int' and 'str'")
        return load(path, world, **kw)

    class Fails(System):
        def run(self, world, dt) -> None:
            raise RuntimeError("a system failed")

    build = Session._build

    def built(self, scene, path):
        world, schedule = build(self, scene, path)
        if Path(scene).stem == "system":
            schedule.add(Fails(), "update")
        return world, schedule

    browser = editor_module.Editor._browser

    def browse(self, world):
        if Path(self.settings.scene).stem == "ui":
            raise KeyError("column")
        browser(self, world)

    monkeypatch.setattr(session_module, "load_world", loader)
    monkeypatch.setattr(Session, "_build", built)
    monkeypatch.setattr(editor_module.Editor, "_browser", browse)
    opens = {2 + FRAMES_PER_OPEN * k: paths[name] for k, name in enumerate(names)}
    frames = 2 + FRAMES_PER_OPEN * len(opens) + 2
    result, session, editor = editor_run(start, opens, frames, tmp_path)
    assert result.frames == frames and session.scene == start
    check_refused(editor.seen, opens, start)
    statuses = [editor.seen[f + FRAMES_PER_OPEN - 1][2] for f in opens]
    assert "cannot be opened (TypeError: unsupported operand" in statuses[0]
    assert "cannot run: RuntimeError: a system failed" in statuses[1]
    assert "cannot run: KeyError: 'column'" in statuses[2]
