"""The input resource: keys, mouse buttons and gamepad buttons by name, gamepad axes, the mouse.

Names: every key GLFW names, lower case without KEY_ (`left_shift`, `f12`, `space`, `0`);
`mouse_left`, `mouse_right`, `mouse_middle`; the gamepad buttons of GLFW's standard mapping
(`gamepad_a`, `gamepad_b`, `gamepad_x`, `gamepad_y`, `gamepad_left_bumper`, `gamepad_back`,
`gamepad_start`, `gamepad_guide`, `gamepad_left_thumb`, `gamepad_dpad_up`, ...) and its axes
(`gamepad_left_x`, `gamepad_left_y`, `gamepad_right_x`, `gamepad_right_y`,
`gamepad_left_trigger`, `gamepad_right_trigger`). A gamepad name stands for every connected
gamepad at once (a button is down while any pad holds it; an axis is the value of the pad
furthest from rest); `InputState.gamepads` keeps each pad's own state for games that tell them apart.
"""

from __future__ import annotations

import difflib
import functools
from dataclasses import dataclass, field

MOUSE_BUTTONS = ("mouse_left", "mouse_right", "mouse_middle")
DEAD_ZONE = 0.15  # of a gamepad axis' travel: sticks rarely rest at exactly 0
# GLFW's aliases of the face buttons (PlayStation names) and its LAST markers: not separate inputs
_GAMEPAD_ALIASES = ("CROSS", "CIRCLE", "SQUARE", "TRIANGLE", "LAST")


@functools.cache
def gamepad_buttons() -> tuple[str, ...]:
    """The standard mapping's buttons by GLFW index: ("gamepad_a", "gamepad_b", ...)."""
    import glfw

    names = {
        getattr(glfw, k): "gamepad_" + k[15:].lower()
        for k in dir(glfw)
        if k.startswith("GAMEPAD_BUTTON_") and k[15:] not in _GAMEPAD_ALIASES
    }
    return tuple(names[i] for i in range(len(names)))


@functools.cache
def gamepad_axes() -> tuple[str, ...]:
    """The standard mapping's axes by GLFW index: ("gamepad_left_x", ..., "gamepad_right_trigger")."""
    import glfw

    names = {
        getattr(glfw, k): "gamepad_" + k[13:].lower()
        for k in dir(glfw)
        if k.startswith("GAMEPAD_AXIS_") and k[13:] not in _GAMEPAD_ALIASES
    }
    return tuple(names[i] for i in range(len(names)))


@functools.cache
def input_names() -> frozenset[str]:
    """Every key GLFW names (KEY_LEFT_SHIFT is "left_shift", KEY_F12 "f12", KEY_0 "0"), the
    mouse buttons and the gamepad buttons: the names InputState's buttons take."""
    import glfw

    keys = {k[4:].lower() for k in dir(glfw) if k.startswith("KEY_") and k not in ("KEY_UNKNOWN", "KEY_LAST")}
    return frozenset(keys | set(MOUSE_BUTTONS) | set(gamepad_buttons()))


def _unknown(name: str, known: frozenset[str] | tuple[str, ...], what: str) -> ValueError:
    near = difflib.get_close_matches(name, sorted(known), n=3)
    hint = f"; did you mean {', '.join(near)}?" if near else ""
    return ValueError(f"unknown {what} {name!r}{hint}")


def dead_zoned(value: float, dead_zone: float) -> float:
    """`value` with |value| < dead_zone as 0 and the rest rescaled, so the output still spans
    [-1, 1] continuously."""
    size = abs(value)
    if size <= dead_zone:
        return 0.0
    return max(-1.0, min(1.0, (size - dead_zone) / (1.0 - dead_zone))) * (1.0 if value > 0 else -1.0)


@dataclass
class Gamepad:
    """One connected gamepad's state (by GLFW joystick id in InputState.gamepads): its name,
    the buttons it holds and its axes (raw, triggers from 0 released to 1 pressed)."""

    name: str = ""
    pressed: set[str] = field(default_factory=set)
    axes: dict[str, float] = field(default_factory=dict)


@dataclass
class InputState:
    """World resource filled by the window layer (or an input script): the keys and buttons
    held (`pressed`), those that went down or up since the last frame's systems ran
    (`just_pressed`, `just_released`: a key pressed and released between two frames is in both),
    the gamepad axes (raw; `axis` applies the dead zone), the mouse position (pixels from the top
    left of a `viewport`-sized view), its move, the scroll and the text typed since then, and
    whether the UI owns the mouse or keyboard. The run loop calls `end_frame()` after the
    systems ran."""

    pressed: set[str] = field(default_factory=set)
    just_pressed: set[str] = field(default_factory=set)
    just_released: set[str] = field(default_factory=set)
    mouse: tuple[float, float] = (0.0, 0.0)
    mouse_delta: tuple[float, float] = (0.0, 0.0)
    scroll: tuple[float, float] = (0.0, 0.0)
    text: str = ""
    mouse_captured_by_ui: bool = False
    keyboard_captured_by_ui: bool = False
    axes: dict[str, float] = field(default_factory=dict)
    dead_zone: float = DEAD_ZONE
    gamepads: dict[int, Gamepad] = field(default_factory=dict)
    viewport: tuple[float, float] = (0.0, 0.0)  # the size the mouse position is measured in (0: unknown)
    # the game's view within it: (x0, y0, width, height) in the mouse's units (the editor's Scene
    # window), None: the whole `viewport`; `mouse` stays the window's (its deltas must not jump)
    view: tuple[float, float, float, float] | None = None

    def in_view(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The mouse from the view's top left, and the view's size (see `view`)."""
        if self.view is None:
            return self.mouse, self.viewport
        x0, y0, w, h = self.view
        return (self.mouse[0] - x0, self.mouse[1] - y0), (w, h)

    @staticmethod
    def check(name: str) -> str:
        """`name` if it is a key or button name, else a ValueError with the close matches."""
        if name not in input_names():
            raise _unknown(name, input_names(), "key or button")
        return name

    @staticmethod
    def check_axis(name: str) -> str:
        """`name` if it is a gamepad axis name, else a ValueError with the close matches."""
        if name not in gamepad_axes():
            raise _unknown(name, gamepad_axes(), "gamepad axis")
        return name

    def down(self, name: str) -> bool:
        """Held now."""
        return self.check(name) in self.pressed

    def pressed_now(self, name: str) -> bool:
        """Went down since the last frame."""
        return self.check(name) in self.just_pressed

    def released_now(self, name: str) -> bool:
        """Went up since the last frame."""
        return self.check(name) in self.just_released

    def axis(self, name: str, dead_zone: float | None = None) -> float:
        """A gamepad axis in [-1, 1] (triggers [0, 1]), 0 inside the dead zone (this state's
        `dead_zone` unless given); 0 with no gamepad."""
        raw = self.axes.get(self.check_axis(name), 0.0)
        return dead_zoned(raw, self.dead_zone if dead_zone is None else dead_zone)

    def press(self, name: str) -> None:
        self.pressed.add(name)
        self.just_pressed.add(name)

    def release(self, name: str) -> None:
        if name in self.pressed:
            self.pressed.discard(name)
            self.just_released.add(name)

    def set_axis(self, name: str, value: float) -> None:
        self.axes[name] = max(-1.0, min(1.0, float(value)))

    def move_mouse(self, x: float, y: float) -> None:
        self.mouse_delta = (self.mouse_delta[0] + x - self.mouse[0], self.mouse_delta[1] + y - self.mouse[1])
        self.mouse = (x, y)

    def end_frame(self) -> None:
        """The frame's systems saw the edges: clear them (the held keys and the axes stay)."""
        self.just_pressed.clear()
        self.just_released.clear()
        self.mouse_delta, self.scroll, self.text = (0.0, 0.0), (0.0, 0.0), ""
