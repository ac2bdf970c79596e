"""Gamepads through GLFW's joystick API, polled once a frame by the window source.

Each joystick GLFW recognises as a gamepad (`glfw.joystick_is_gamepad`) is read with
`glfw.get_gamepad_state` (the standard mapping: 15 buttons, 6 axes). `reading()` turns one such
result into names; `GamepadPoller.update()` puts the readings of all pads into the InputState:
a button goes down when the first pad presses it and up when the last pad holding it lets go
or goes away (unplugged: its buttons are released, its axes return to 0), with the same
this-frame edges as keys. Axes are written when a pad moves them, so a value an input script
set stays until a real pad changes it. Triggers rest at -1 in GLFW's mapping; here they run
from 0 (released) to 1 (pressed), like a button's travel. Tests feed `update` with fake
readings: CI has no gamepad.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..systems.input_state import Gamepad, InputState, gamepad_axes, gamepad_buttons

TRIGGERS = ("gamepad_left_trigger", "gamepad_right_trigger")


def reading(raw: tuple[Sequence[int], Sequence[float]] | Any, name: str = "") -> Gamepad:
    """One `glfw.get_gamepad_state` result ((buttons, axes): 0/1 per button, -1..1 per axis) as a
    Gamepad: the names of the buttons held and the axes (triggers as 0..1)."""
    buttons, axes = raw
    pad = Gamepad(name=name)
    pad.pressed = {n for n, value in zip(gamepad_buttons(), buttons) if value}
    for n, value in zip(gamepad_axes(), axes):
        value = float(value)
        pad.axes[n] = (value + 1.0) * 0.5 if n in TRIGGERS else value
    return pad


def read_gamepads(glfw: Any) -> dict[int, Gamepad]:
    """Every connected gamepad's state, by joystick id (none: an empty dict)."""
    pads = {}
    for jid in range(glfw.JOYSTICK_1, glfw.JOYSTICK_LAST + 1):
        if not glfw.joystick_is_gamepad(jid):
            continue
        raw = glfw.get_gamepad_state(jid)
        if raw is not None:  # went away between the two calls
            pads[jid] = reading(raw, glfw.get_gamepad_name(jid) or "")
    return pads


class GamepadPoller:
    """Keeps what the pads held and showed last frame, so only changes reach the InputState."""

    def __init__(self) -> None:
        self.held: set[str] = set()
        self.axes: dict[str, float] = {}

    def poll(self, glfw: Any, state: InputState) -> None:
        self.update(state, read_gamepads(glfw))

    def update(self, state: InputState, pads: dict[int, Gamepad]) -> None:
        """This frame's gamepads (by joystick id) into `state`: per pad in `state.gamepads`,
        and together under the gamepad names."""
        state.gamepads = dict(pads)
        held = set().union(*(pad.pressed for pad in pads.values()))
        for name in sorted(held - self.held):
            state.press(name)
        for name in sorted(self.held - held):
            state.release(name)
        self.held = held
        axes = {}
        for name in gamepad_axes():
            values = [pad.axes.get(name, 0.0) for pad in pads.values()]
            # two pads: the one further from rest (the one being used)
            axes[name] = max(values, key=abs) if values else 0.0
            if axes[name] != self.axes.get(name, 0.0):
                state.set_axis(name, axes[name])
        self.axes = axes
