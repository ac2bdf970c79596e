"""An input script's events for ImGui, so the editor and a game's HUD can be driven (and tested)
by `--input-script` as the game is: keys and mouse buttons as ImGui key and button events (with
the Ctrl, Shift, Alt and Super modifiers ImGui's shortcuts read), the pointer, the wheel and
typed text. Real input reaches ImGui through its GLFW backend; this is only the script's.

The events of a frame are queued and handed to ImGui when the UI is next built (the UI may skip
frames: imgui_session.py), after the GLFW backend's own, so that in a window the backend's
"where the real cursor is" does not move the script's pointer: once a script has moved the
pointer, ImGui follows the script's pointer, not the real one, until the run ends. Gamepad
buttons and axes are left out (the editor does not navigate by gamepad).
"""

from __future__ import annotations

import functools
from collections.abc import Iterable
from typing import Any

MOUSE_BUTTONS = {"mouse_left": 0, "mouse_right": 1, "mouse_middle": 2}
# InputState name -> the ImGui modifier it holds (ImGui reads Ctrl+O as Key.mod_ctrl plus Key.o)
MODIFIERS = {
    **dict.fromkeys(("left_control", "right_control"), "mod_ctrl"),
    **dict.fromkeys(("left_shift", "right_shift"), "mod_shift"),
    **dict.fromkeys(("left_alt", "right_alt"), "mod_alt"),
    **dict.fromkeys(("left_super", "right_super"), "mod_super"),
}
# InputState (GLFW) names whose ImGui key is named otherwise
_RENAMED = {
    "left_control": "left_ctrl",
    "right_control": "right_ctrl",
    "left": "left_arrow",
    "right": "right_arrow",
    "up": "up_arrow",
    "down": "down_arrow",
    "world_1": "oem102",
}


@functools.cache
def imgui_keys() -> dict[str, Any]:
    """InputState key name -> ImGui key, for every key both know ("0" -> Key._0, "kp_add" ->
    Key.keypad_add, "left_control" -> Key.left_ctrl, "escape" -> Key.escape, ...)."""
    from imgui_bundle import imgui

    from ..systems.input_state import input_names

    keys = {}
    for name in input_names():
        wanted = _RENAMED.get(name, name)
        if wanted.isdigit():
            wanted = f"_{wanted}"
        elif wanted.startswith("kp_"):
            wanted = "keypad" + (wanted[3:] if wanted[3:].isdigit() else "_" + wanted[3:])
        key = getattr(imgui.Key, wanted, None)
        if key is not None:
            keys[name] = key
    return keys


class ScriptedImGuiInput:
    def __init__(self, imgui: Any, windowed: bool) -> None:
        self.imgui = imgui
        self.windowed = windowed
        self.pending: list[tuple[str, ...]] = []
        self.pointer: tuple[float, float] | None = None  # where the script last put the mouse
        self.held: set[str] = set()  # modifier keys the script holds

    def queue(self, events: Iterable[tuple[str, ...]]) -> None:
        """A frame's events (InputScript.events' tuples: action, *arguments)."""
        self.pending.extend(events)

    def flush(self) -> None:
        """The queued events into ImGui's input queue (between the backend's new frame and
        imgui.new_frame)."""
        io = self.imgui.get_io()
        if self.windowed and self.pointer is not None:
            io.add_mouse_pos_event(*self.pointer)  # after the backend's real cursor
        for action, *args in self.pending:
            if action in ("down", "up"):
                self._button(io, args[0], action == "down")
            elif action == "move":
                self.pointer = (float(args[0]), float(args[1]))
                io.add_mouse_pos_event(*self.pointer)
            elif action == "scroll":
                io.add_mouse_wheel_event(float(args[0]), float(args[1]))
            elif action == "text":
                io.add_input_characters_utf8(args[0])
        self.pending.clear()

    def _button(self, io: Any, name: str, down: bool) -> None:
        if name in MOUSE_BUTTONS:
            io.add_mouse_button_event(MOUSE_BUTTONS[name], down)
            return
        key = imgui_keys().get(name)
        if key is None:  # a gamepad button
            return
        modifier = MODIFIERS.get(name)
        if modifier is not None:
            (self.held.add if down else self.held.discard)(name)
            held = any(MODIFIERS[other] == modifier for other in self.held)
            io.add_key_event(getattr(self.imgui.Key, modifier), held)
        io.add_key_event(key, down)
