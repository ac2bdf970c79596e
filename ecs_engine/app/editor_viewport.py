"""The editor's Scene window: an ImGui window docked into the dock space's central node that shows
the renderer's viewport image (render/frame/viewport.py) at exactly its content's pixel size, so
the scene is drawn there alone and never under the panels. Each UI build lays it out before the
frame is rendered, so the frame draws at the size just laid out (no lag).

Clicks and the gizmo work in its own coordinates: `rect` is the image's rectangle in ImGui's
points, `hovered` whether the pointer is over the image (ImGui reports the UI as having the
mouse there, so the editor asks `hovered`, not `want_capture_mouse`). Closed, undocked into a
collapsed window or not built: `viewport.size` is None and the renderer draws the whole window.
"""

from __future__ import annotations

import math
from typing import Any

from .editor_dock import SCENE as NAME


class SceneWindow:
    """Build with `begin(...)`, then whatever draws over the scene (the gizmo), then `end()`."""

    def __init__(self, imgui: Any) -> None:
        self.imgui = imgui
        self.rect: tuple[float, float, float, float] | None = None  # (x0, y0, x1, y1) points
        self.hovered = False
        self.scale = (1.0, 1.0)  # pixels per point (ImGui's framebuffer scale)

    def begin(self, viewport: Any, ui: Any, window: Any, dock_id: int = 0) -> bool:
        """The window with the viewport's image (`ui`: the ImGuiRenderer; `window`: the
        renderer's window target, whose size bounds the image); False when it shows nothing
        (call `end()` either way). `dock_id`: the central node, where it goes the first time
        (an editor.ini from before it existed has no place for it)."""
        imgui = self.imgui
        was_hovered = self.hovered
        self.rect, self.hovered = None, False
        viewport.size = None
        if dock_id:
            imgui.set_next_window_dock_id(dock_id, imgui.Cond_.first_use_ever.value)
        hidden = imgui.WindowClass()
        hidden.dock_node_flags_override_set = imgui.DockNodeFlags_.auto_hide_tab_bar.value
        imgui.set_next_window_class(hidden)
        flags = imgui.WindowFlags_
        chosen = flags.no_scrollbar.value | flags.no_scroll_with_mouse.value | flags.no_collapse.value
        if was_hovered:  # a drag over the scene moves the gizmo or the camera, not the window
            chosen |= flags.no_move.value
        # no padding and no border: the image fills the window, none of its pixels drawn over
        imgui.push_style_var(imgui.StyleVar_.window_padding.value, (0.0, 0.0))
        imgui.push_style_var(imgui.StyleVar_.window_border_size.value, 0.0)
        shown = imgui.begin(NAME, None, chosen)[0]
        imgui.pop_style_var(2)
        if not shown:
            return False
        io = imgui.get_io()
        scale = io.display_framebuffer_scale
        sx, sy = max(float(scale.x), 1e-6), max(float(scale.y), 1e-6)
        self.scale = (sx, sy)
        p0 = imgui.get_cursor_screen_pos()
        avail = imgui.get_content_region_avail()
        w, h = math.floor(avail.x * sx), math.floor(avail.y * sy)
        if w <= 0 or h <= 0:
            return False
        viewport.size = (w, h)
        tex_id, (cap_w, cap_h) = viewport.texture(ui, window)
        w, h = min(w, int(cap_w)), min(h, int(cap_h))
        size = (w / sx, h / sy)
        imgui.image(imgui.ImTextureRef(tex_id), size, (0.0, 0.0), (w / cap_w, h / cap_h))
        self.hovered = bool(imgui.is_item_hovered())
        self.rect = (p0.x, p0.y, p0.x + size[0], p0.y + size[1])
        return True

    def end(self) -> None:
        self.imgui.end()

    def view(self) -> tuple[float, float, float, float] | None:
        """(x0, y0, width, height) of the image in points (the mouse's units), or None."""
        if self.rect is None:
            return None
        x0, y0, x1, y1 = self.rect
        return (x0, y0, x1 - x0, y1 - y0)


def scene_input(editor: Any, world: Any) -> None:
    """The Scene window (when the editor has a viewport: `editor.viewport`), the gizmo over the
    selection inside it, a click on the scene picks, Ctrl+Z / Ctrl+Y undo and redo, W / E / R
    pick the gizmo's operation (while no text field has the keyboard). Without a Scene window
    (none given, closed, collapsed) the scene is the whole window, under the panels."""
    from ..components import Transform

    imgui = editor.imgui
    io = imgui.get_io()
    width, height = io.display_size.x, io.display_size.y
    scene, viewport = editor.scene, editor.viewport
    began = viewport is not None
    if began:
        ui, window = editor.viewport_ui
        central = imgui.internal.dock_builder_get_central_node(editor.dock.id) if editor.dock.id else None
        scene.begin(viewport, ui, window(), central.id_ if central is not None else 0)
    else:
        scene.rect, scene.hovered = None, False
    try:
        inside = scene.rect is not None  # drawn over the image, clipped to the window
        rect = scene.rect if inside else (0.0, 0.0, width, height)
        editor.physics.draw_colliders(imgui, world, rect, imgui.get_window_draw_list() if inside else None)
        animated = editor.animated  # the character the Animation window shows (editor_animation.py)
        editor.animation.draw_skeleton(imgui, world, animated, rect, imgui.get_window_draw_list() if inside else None)
        eid = editor.selected
        editor.gizmo.used = False
        if eid is not None and world.is_alive(eid) and world.has(eid, Transform):
            drawlist = imgui.get_window_draw_list() if inside else None
            editor.gizmo.draw(world, eid, editor.history, rect, drawlist)
    finally:
        if began:
            scene.end()
    if not io.want_text_input:
        ctrl = imgui.Key.mod_ctrl
        if imgui.is_key_chord_pressed(ctrl | imgui.Key.z):
            editor.history.undo(world)
        elif imgui.is_key_chord_pressed(ctrl | imgui.Key.y) or imgui.is_key_chord_pressed(
            ctrl | imgui.Key.mod_shift | imgui.Key.z
        ):
            editor.history.redo(world)
        from .editor_gizmo import OPERATIONS

        for key, operation in zip((imgui.Key.w, imgui.Key.e, imgui.Key.r), OPERATIONS):
            if not io.key_ctrl and imgui.is_key_pressed(key, False) and not io.want_capture_keyboard:
                editor.gizmo.operation = operation
    # over the Scene window ImGui has the mouse (want_capture_mouse): its image is the scene
    over = scene.hovered if scene.rect is not None else not io.want_capture_mouse
    if imgui.is_mouse_clicked(0) and over and not editor.gizmo.used and editor.meshes is not None:
        from ..render.picking import pick

        mouse = io.mouse_pos
        if scene.rect is not None:  # in the image's pixels, its picture the whole view
            x0, y0, x1, y1 = scene.rect
            sx, sy = scene.scale
            at = ((mouse.x - x0) * sx, (mouse.y - y0) * sy, (x1 - x0) * sx, (y1 - y0) * sy)
        else:
            at = (mouse.x, mouse.y, max(width, 1.0), max(height, 1.0))
        hit = pick(world, editor.meshes, *at)
        editor.picked = None if hit is None else hit.entity
        if hit is not None:
            editor.selected = hit.entity
