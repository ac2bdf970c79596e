"""The editor's File menu: Open, Save and Save as of scene files (ecs/scene_file.py), in the main
menu bar above the docked panels, with Ctrl+O and Ctrl+S.

- Save writes the world the editor shows, its meshes, materials and environment by reference
  where they can be made again (render/assets/scene_assets.py), to the scene file it came from; a scene
  that came from no file asks for a path first (Save as). A failed save keeps the old file.
- Open asks for a path and requests it as the next scene, like any scene switch: the run loop's
  Session.apply loads it between frames; a bad file is refused with one line (in the menu bar and
  under the scene settings) and the scene in use stays. So is one that loads but fails in its
  first frames (a Parent loop, a missing environment file): the loop goes back to the scene
  before it (Session.roll_back). Opening a file never ends the editor.

The dialog is ImGui's own (a path field and the scene files of its folder), so it works the same
headless, under Xvfb and in tests; no desktop file chooser is needed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..ecs.errors import EcsError
from ..ecs.scene_file import save_world
from ..ecs.world import World
from ..render.assets.scene_assets import scene_codecs
from .scenes import SCENE_FILE_SUFFIX, is_scene_file

OPEN, SAVE = "Open scene", "Save scene as"
MAX_LISTED = 200  # scene files of the folder shown in the dialog


@dataclass
class FileMenu:
    path: str = ""  # the dialog's path field
    status: str = ""  # what the last save or open did, shown in the menu bar
    failed: bool = False
    dialog: str | None = None  # OPEN or SAVE while the dialog is to be shown
    focus: bool = False  # give the path field the keyboard on the dialog's first frame
    pending: str | None = None  # a file requested as the next scene, until the loop applied it
    # screen rectangles (x0, y0, x1, y1) of the menu and its items as last drawn: where synthetic
    # input (tests, scripted runs) should click
    rects: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)

    def draw(self, imgui: Any, world: World, editor: Any) -> None:
        """The menu bar, the shortcuts and the dialog (call before the dock space: the menu bar
        takes its height from the window's work area)."""
        if self.pending is not None and editor.requested == editor.settings:  # the loop answered
            opened = editor.settings.scene == self.pending
            self._done(f"opened {self.pending}" if opened else editor.settings_status, failed=not opened)
            if not opened:
                _unlisted(editor, self.pending)
            self.pending = None
        if imgui.begin_main_menu_bar():
            opened = imgui.begin_menu("File")
            if not opened:  # (open, the last item is the menu's window)
                self._remember(imgui, "File")
            if opened:
                if imgui.menu_item("Open...", "Ctrl+O", False)[0]:
                    self.ask(OPEN, editor)
                self._remember(imgui, "Open...")
                if imgui.menu_item("Save", "Ctrl+S", False)[0]:
                    self.save_or_ask(world, editor)
                if imgui.menu_item("Save as...", "", False)[0]:
                    self.ask(SAVE, editor)
                imgui.end_menu()
            if self.status:
                colour = (1.0, 0.4, 0.3, 1.0) if self.failed else (0.6, 0.9, 0.6, 1.0)
                imgui.text_colored(colour, self.status)
            imgui.end_main_menu_bar()
        io = imgui.get_io()
        if not io.want_text_input and self.dialog is None:
            if imgui.is_key_chord_pressed(imgui.Key.mod_ctrl | imgui.Key.s):
                self.save_or_ask(world, editor)
            elif imgui.is_key_chord_pressed(imgui.Key.mod_ctrl | imgui.Key.o):
                self.ask(OPEN, editor)
        self._dialog(imgui, world, editor)

    # ------------------------------------------------------------------ actions
    def ask(self, dialog: str, editor: Any) -> None:
        current = editor.settings.scene
        self.path = current if is_scene_file(current) else str(Path.cwd() / f"{current}{SCENE_FILE_SUFFIX}")
        self.dialog, self.focus = dialog, True

    def save_or_ask(self, world: World, editor: Any) -> None:
        current = editor.settings.scene
        if is_scene_file(current):
            self.save(world, editor, current)
        else:
            self.ask(SAVE, editor)

    def save(self, world: World, editor: Any, path: str) -> bool:
        """Write `world` to `path` (.scene added when it has no suffix); the result is the status."""
        file = Path(path).expanduser()
        if not file.suffix:
            file = file.with_suffix(SCENE_FILE_SUFFIX)
        if not is_scene_file(str(file)):
            return self._done(f"a scene file's name ends in {SCENE_FILE_SUFFIX}: {file.name}", failed=True)
        if editor.meshes is None:
            return self._done("no renderer meshes to save the scene's meshes with", failed=True)
        try:
            save_world(world, file, resources=scene_codecs(editor.meshes))
        except (EcsError, ValueError, OSError) as exc:
            return self._done(str(exc), failed=True)
        if not is_scene_file(editor.settings.scene):  # offer the new file in the scene switcher
            _listed(editor, str(file))
        return self._done(f"saved {len(world):,} entities to {file}")

    def open(self, editor: Any, path: str) -> bool:
        """Request the scene file at `path` as the next scene (the run loop applies it)."""
        file = Path(path).expanduser()
        if not is_scene_file(str(file)):
            return self._done(f"not a {SCENE_FILE_SUFFIX} file: {file.name}", failed=True)
        if not file.is_file():
            return self._done(f"no scene file {file}", failed=True)
        name = _listed(editor, str(file))
        editor.requested.scene = self.pending = name
        return self._done(f"opening {file}")

    def failed_after_opening(self, editor: Any, scene: str, message: str) -> None:
        """`scene` loaded but failed in its first frames (the run loop went back to the one
        before it): the menu bar says so instead of "opened", and the scene switcher no longer
        offers it."""
        self.pending = None
        _unlisted(editor, scene)
        self._done(message, failed=True)

    def _remember(self, imgui: Any, name: str) -> None:
        lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
        self.rects[name] = (lo.x, lo.y, hi.x, hi.y)

    def _done(self, status: str, failed: bool = False) -> bool:
        self.status, self.failed = status, failed
        return not failed

    # ------------------------------------------------------------------- dialog
    def _dialog(self, imgui: Any, world: World, editor: Any) -> None:
        if self.dialog is None:
            return
        title = self.dialog
        if not imgui.is_popup_open(title):
            imgui.open_popup(title)
        imgui.set_next_window_size((520, 320), imgui.Cond_.appearing.value)
        if not imgui.begin_popup_modal(title)[0]:
            self.dialog = None
            return
        if self.focus:
            imgui.set_keyboard_focus_here()
            self.focus = False
        entered, self.path = imgui.input_text("path", self.path, imgui.InputTextFlags_.enter_returns_true.value)
        imgui.text_disabled(f"{SCENE_FILE_SUFFIX} files here:")
        if imgui.begin_child("files", (0, -imgui.get_frame_height_with_spacing())):
            for file in _scene_files(self.path):
                if imgui.selectable(file.name, str(file) == self.path)[0]:
                    self.path = str(file)
        imgui.end_child()
        confirmed = imgui.button("Open" if title == OPEN else "Save") or entered
        imgui.same_line()
        cancelled = imgui.button("Cancel") or imgui.is_key_pressed(imgui.Key.escape)
        if confirmed:
            done = self.open(editor, self.path) if title == OPEN else self.save(world, editor, self.path)
            cancelled = done  # a refused path keeps the dialog open, its reason in the menu bar
        if cancelled:
            self.dialog = None
            imgui.close_current_popup()
        imgui.end_popup()


def _listed(editor: Any, name: str) -> str:
    """`name` in the editor's scene switcher (added once)."""
    if name not in editor.scenes:
        editor.scenes = (*editor.scenes, name)
    return name


def _unlisted(editor: Any, name: str) -> None:
    """A scene file that cannot be opened out of the scene switcher (unless it is in use)."""
    if name != editor.settings.scene:
        editor.scenes = tuple(s for s in editor.scenes if s != name)


def _scene_files(path: str) -> list[Path]:
    """The scene files in the folder of `path` (the folder itself when it is one)."""
    folder = Path(path).expanduser()
    folder = folder if folder.is_dir() else folder.parent
    try:
        found = sorted(p for p in folder.iterdir() if p.suffix.lower() == SCENE_FILE_SUFFIX and p.is_file())
    except OSError:
        return []
    return found[:MAX_LISTED]
