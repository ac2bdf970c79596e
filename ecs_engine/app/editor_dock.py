"""The editor's docked layout: a dock space over the whole window whose central node holds the
Scene window (editor_viewport.py: the renderer's viewport image), with the panels docked around
it: scene settings down the left, the inspector down the right, and under the scene the entity
browser and the hierarchy (tabs) beside the Perf window (and the Sound window, a tab of it). In
a window narrower than `WIDE` the space under the scene would give those two panels under 250
pixels each, so the browser goes under the settings and Perf under the inspector instead, and
the scene keeps the middle from top to bottom. The user may rearrange them; ImGui keeps the
layout in `editor.ini` in the user's config folder (XDG_CONFIG_HOME, else ~/.config, then
`ecs_engine/`), so it is the same next run. The default layout is built only when that file has
none. A headless editor always has the default layout and leaves the file alone."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..user_dirs import config_home

LEFT = ("Scene and render",)
RIGHT = ("Inspector",)
BOTTOM_LEFT = ("Hierarchy", "Entities")  # tabs; the entity browser in front
BOTTOM_RIGHT = ("Perf", "Sound")  # tabs; the Sound window (editor_audio.py) only while there is sound
PANEL_WIDTH = 300.0  # pixels the side columns get at least (up to 40% of the window each)
WIDE = 1200.0  # pixels: from this width the browser and Perf go under the scene
DOCKSPACE = "editor dock space"
SCENE = "Scene"  # editor_viewport.py's window


def config_dir() -> Path:
    """The user's config folder for the engine (created when first written)."""
    return config_home() / "ecs_engine"


def layout_file() -> Path:
    return config_dir() / "editor.ini"


def in_a_window(io: Any) -> bool:
    """Whether this ImGui draws into a window: its GLFW backend, set up before the editor, names
    itself (a headless editor has no platform backend)."""
    return bool(io.backend_platform_name)


class DockLayout:
    """Call `begin()` first in every UI frame (after imgui.new_frame)."""

    def __init__(self, imgui: Any, persist: bool = True) -> None:
        self.imgui = imgui
        io = imgui.get_io()
        io.config_flags |= imgui.ConfigFlags_.docking_enable.value
        self.path: Path | None = None
        # Only a window's editor keeps the user's layout: a headless one neither reads nor writes
        # editor.ini, so its image is the default layout on every machine and the user's file
        # stays as they left it.
        if persist and in_a_window(io):
            self.path = layout_file()
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                io.set_ini_filename(str(self.path))
            except OSError:  # a read-only home: the layout is not kept, nothing else changes
                self.path = None
        self.id = 0
        self.central: tuple[float, float, float, float] | None = None  # the scene's rectangle
        self._checked = False

    def begin(self) -> None:
        imgui = self.imgui
        flags = imgui.DockNodeFlags_.passthru_central_node.value
        self.id = imgui.dock_space_over_viewport(imgui.get_id(DOCKSPACE), imgui.get_main_viewport(), flags)
        internal = imgui.internal
        if not self._checked:
            self._checked = True
            node = internal.dock_builder_get_node(self.id)
            if node is None or not node.is_split_node():
                self.build_default()
        central = internal.dock_builder_get_central_node(self.id)
        if central is not None:
            x, y = central.pos.x, central.pos.y
            self.central = (x, y, x + central.size.x, y + central.size.y)

    def region(self, width: float, height: float) -> tuple[float, float, float, float] | None:
        """The central node as fractions of a width x height window (the renderer's region: the
        scene shows there, centred and undistorted), or None before the first layout."""
        if self.central is None or width <= 0 or height <= 0:
            return None
        px0, py0, px1, py1 = (round(v) for v in self.central)  # whole pixels: the view's pixels are the window's
        x0, x1 = min(max(px0 / width, 0.0), 1.0), min(max(px1 / width, 0.0), 1.0)
        y0, y1 = min(max(py0 / height, 0.0), 1.0), min(max(py1 / height, 0.0), 1.0)
        return (x0, y0, x1, y1) if x1 - x0 > 1e-3 and y1 - y0 > 1e-3 else None  # a collapsed node: whole window

    def build_default(self) -> None:
        imgui, internal = self.imgui, self.imgui.internal
        viewport = imgui.get_main_viewport()
        internal.dock_builder_remove_node(self.id)
        internal.dock_builder_add_node(self.id, imgui.internal.DockNodeFlagsPrivate_.dock_space.value)
        internal.dock_builder_set_node_size(self.id, viewport.size)
        side = min(max(PANEL_WIDTH / max(viewport.size.x, 1.0), 0.2), 0.4)
        left, rest = internal.dock_builder_split_node_py(self.id, imgui.Dir.left, side)[1:]
        right, rest = internal.dock_builder_split_node_py(rest, imgui.Dir.right, min(side / (1.0 - side), 0.5))[1:]
        if viewport.size.x >= WIDE:
            bottom, _ = internal.dock_builder_split_node_py(rest, imgui.Dir.down, 0.3)[1:]
            browser, perf = internal.dock_builder_split_node_py(bottom, imgui.Dir.left, 0.45)[1:]
        else:
            browser, left = internal.dock_builder_split_node_py(left, imgui.Dir.down, 0.4)[1:]
            perf, right = internal.dock_builder_split_node_py(right, imgui.Dir.down, 0.45)[1:]
        for names, node in ((LEFT, left), (RIGHT, right), (BOTTOM_LEFT, browser), (BOTTOM_RIGHT, perf)):
            for name in names:
                internal.dock_builder_dock_window(name, node)
        central = internal.dock_builder_get_central_node(self.id)
        if central is not None:  # the scene's window (editor_viewport.py) fills the central node
            internal.dock_builder_dock_window(SCENE, central.id_)
        internal.dock_builder_finish(self.id)
