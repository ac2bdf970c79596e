"""Named actions bound to inputs: a game asks for "fire" or "turn", not for space or a stick.

An action is a button action (bound to keys, mouse buttons or gamepad buttons: down while any of
them is held) or an axis action (a float in [-1, 1], the sum of its bindings, clipped: a gamepad
axis, `-gamepad_left_y` for one reversed, or a pair of buttons `a/d`, -1 for the first, +1 for
the second). Its kind is fixed by its first binding, so a rebinding (at run time, or from the
user's file) cannot turn a game's axis into a button. Bindings are strings, the same in code
and in the JSON file:

    actions = ActionMap({"fire": ["space", "mouse_left", "gamepad_a"], "turn": ["a/d", "gamepad_left_x"]})
    actions.bind("fire", "left_control", "gamepad_right_bumper")  # replaces fire's bindings

Queries read the InputState in `actions.input` (`ActionMap.of(world)` gives the world's map
reading the world's input). Mouse buttons count for nothing while the UI has the mouse
(`mouse_captured_by_ui`), keys nothing while it has the keyboard; gamepads always count.

The file (`save`, `load`) is JSON: {"version": 1, "dead_zone": 0.15, "actions": {name: [binding,
...]}}; actions it leaves out keep their defaults. Anything wrong in it is one InputConfigError
naming the file and the problem.
"""

from __future__ import annotations

import difflib
import json
import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ecs_engine.ecs.world import World
from ecs_engine.errors import UsageError
from ecs_engine.user_files import BINDINGS, UserFileError, read_user_file
from ecs_engine.user_json import parse_json

from .input_state import MOUSE_BUTTONS, InputState, gamepad_axes, input_names

VERSION = 1
BUTTON, AXIS = "button", "axis"
FILE_KEYS = ("version", "dead_zone", "actions")


class InputConfigError(UsageError):
    """A bindings file that cannot be used (the message names the file and the problem)."""


def _close(name: str, known: Iterable[str]) -> str:
    near = difflib.get_close_matches(name, sorted(known), n=3)
    return f"; did you mean {', '.join(near)}?" if near else ""


@dataclass(frozen=True)
class Binding:
    """One parsed binding: `kind` "button" (names = (button,)), "analog" (names = (axis,),
    sign -1 when written with a leading -) or "pair" (names = (minus, plus))."""

    text: str
    kind: str
    names: tuple[str, ...]
    sign: float = 1.0

    @property
    def action_kind(self) -> str:
        return BUTTON if self.kind == "button" else AXIS


def parse_binding(text: str) -> Binding:
    """A binding string, checked: a ValueError with the close matches for an unknown name."""
    if not isinstance(text, str):
        raise ValueError(f"a binding is a string (a key, button or axis name), not {text!r}")
    if "/" in text:
        parts = text.split("/")
        if len(parts) != 2 or not all(parts):
            raise ValueError(f"a button pair is written 'minus/plus' (like 'a/d'), not {text!r}")
        return Binding(text, "pair", tuple(_button(p) for p in parts))
    name = text[1:] if text.startswith("-") else text
    if name in gamepad_axes():
        return Binding(text, "analog", (name,), -1.0 if text.startswith("-") else 1.0)
    if text.startswith("-"):
        raise ValueError(f"only an axis can be reversed with '-': {text!r}{_close(name, gamepad_axes())}")
    return Binding(text, "button", (_button(text),))


def _button(name: str) -> str:
    if name not in input_names():
        known = input_names() | set(gamepad_axes())
        raise ValueError(f"unknown key, button or axis {name!r}{_close(name, known)}")
    return name


class ActionMap:
    """Actions by name -> their bindings; queries against `input` (see the module doc)."""

    def __init__(
        self,
        bindings: Mapping[str, Iterable[str]] | None = None,
        input: InputState | None = None,
        dead_zone: float | None = None,
    ) -> None:
        self.bindings: dict[str, tuple[Binding, ...]] = {}
        self.kinds: dict[str, str] = {}
        self.input = input if input is not None else InputState()
        self.dead_zone = dead_zone  # None: the InputState's
        for action, inputs in (bindings or {}).items():
            self.bind(action, *inputs)

    @staticmethod
    def of(world: World) -> ActionMap:
        """The world's ActionMap resource, reading the world's InputState (a still one if none)."""
        actions = world.resources.get(ActionMap)
        if actions is None:
            raise KeyError("the world has no ActionMap resource: world.resources[ActionMap] = ActionMap({...})")
        state = world.resources.get(InputState)
        if state is not None:
            actions.input = state
        return actions

    # ----------------------------------------------------------------- bindings
    def bind(self, action: str, *inputs: str) -> None:
        """Replace `action`'s bindings (none: it does nothing until bound again). A new action
        takes the kind of its bindings; an existing one keeps its kind. Nothing changes when a
        binding is refused (a ValueError: unknown name, or the wrong kind)."""
        if not isinstance(action, str) or not action:
            raise ValueError(f"an action name is a non-empty string, not {action!r}")
        parsed = tuple(parse_binding(text) for text in inputs)
        kinds = {b.action_kind for b in parsed}
        kind = self.kinds.get(action) or (kinds.pop() if len(kinds) == 1 else None)
        if kind is None and parsed:
            raise ValueError(
                f"action {action!r} mixes buttons and axes ({', '.join(inputs)}); "
                "an axis action takes axes and button pairs like 'a/d'"
            )
        wrong = [b.text for b in parsed if b.action_kind != kind]
        if wrong:
            hint = "axes or button pairs like 'a/d'" if kind == AXIS else "keys and buttons"
            raise ValueError(f"{action!r} is {'an' if kind == AXIS else 'a'} {kind} action: bind {hint}, not {wrong}")
        self.bindings[action] = parsed
        if kind is not None:
            self.kinds[action] = kind

    def bound(self, action: str) -> list[str]:
        """The binding strings of `action`."""
        return [b.text for b in self.bindings[self._check(action)]]

    def _check(self, action: str, kind: str | None = None) -> str:
        if action not in self.bindings:
            raise ValueError(f"unknown action {action!r}{_close(action, self.bindings)}")
        if kind is not None and self.kinds.get(action, kind) != kind:
            use = "axis()" if kind == BUTTON else "action_down / action_pressed / action_released"
            raise ValueError(f"{action!r} is {'an' if kind == BUTTON else 'a'} {self.kinds[action]} action: use {use}")
        return action

    # ------------------------------------------------------------------ queries
    def _live(self, name: str) -> bool:
        """Whether `name` counts now (the UI has neither the mouse nor the keyboard it is on)."""
        if name in MOUSE_BUTTONS:
            return not self.input.mouse_captured_by_ui
        return name.startswith("gamepad_") or not self.input.keyboard_captured_by_ui

    def _buttons(self, action: str, kind: str) -> list[str]:
        names = [n for b in self.bindings[self._check(action, kind)] for n in b.names]
        return [n for n in names if self._live(n)]

    def action_down(self, action: str) -> bool:
        """Any of the action's buttons held now."""
        return any(n in self.input.pressed for n in self._buttons(action, BUTTON))

    def action_pressed(self, action: str) -> bool:
        """The action went down this frame (none of its buttons was held before)."""
        names, s = self._buttons(action, BUTTON), self.input
        before = any(
            (n in s.pressed and (n not in s.just_pressed or n in s.just_released))
            or (n in s.just_released and n not in s.just_pressed)
            for n in names
        )
        return not before and any(n in s.just_pressed for n in names)

    def action_released(self, action: str) -> bool:
        """The action went up this frame (none of its buttons is held now)."""
        names, s = self._buttons(action, BUTTON), self.input
        return any(n in s.just_released for n in names) and not any(n in s.pressed for n in names)

    def axis(self, action: str) -> float:
        """The axis action's value in [-1, 1]: its bindings summed, clipped."""
        total, s = 0.0, self.input
        for b in self.bindings[self._check(action, AXIS)]:
            if b.kind == "analog":
                total += b.sign * s.axis(b.names[0], self.dead_zone)
            else:
                minus, plus = (n in s.pressed and self._live(n) for n in b.names)
                total += float(plus) - float(minus)
        return max(-1.0, min(1.0, total))

    def pointer(self) -> tuple[float, float] | None:
        """The mouse position (pixels from the top left of the game's view: `input.view`, the
        editor's Scene window, else `input.viewport`), None while the UI has the mouse."""
        return None if self.input.mouse_captured_by_ui else self.input.in_view()[0]

    # --------------------------------------------------------------------- file
    def to_json(self) -> dict[str, Any]:
        actions = {a: [b.text for b in bs] for a, bs in self.bindings.items()}
        data: dict[str, Any] = {"version": VERSION, "actions": actions}
        if self.dead_zone is not None:
            data["dead_zone"] = self.dead_zone
        return data

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write every action's bindings to `path` (JSON), whole or not at all."""
        file = Path(path)
        temporary = file.with_name(file.name + ".tmp")
        try:
            file.parent.mkdir(parents=True, exist_ok=True)
            temporary.write_text(json.dumps(self.to_json(), indent=2) + "\n", encoding="utf-8")
            os.replace(temporary, file)
        except OSError as exc:
            raise InputConfigError(f"input bindings {file}: cannot be written ({exc})") from None

    @classmethod
    def load(cls, path: str | os.PathLike[str], defaults: Mapping[str, Iterable[str]]) -> ActionMap:
        """The defaults with the file's bindings over them. No file: the defaults. A file that
        cannot be used: one InputConfigError naming it and the first problem."""
        actions = cls(defaults)
        file = Path(path)
        if not file.exists():
            return actions
        where = f"input bindings {file}"
        try:  # only a regular file, of bounded size, nesting and numbers (user_files, user_json)
            data = parse_json(read_user_file(file, BINDINGS))
        except UserFileError as exc:
            raise InputConfigError(f"{where}: {exc.why}") from None
        except OSError as exc:
            raise InputConfigError(f"{where}: cannot be read ({exc})") from None
        except ValueError as exc:
            raise InputConfigError(f"{where}: {exc}") from None
        try:
            actions.apply(data)
        except ValueError as exc:
            raise InputConfigError(f"{where}: {exc}") from None
        return actions

    def apply(self, data: Any) -> None:
        """A parsed file's contents over these bindings: all of it, or (a ValueError) none."""
        if not isinstance(data, dict):
            raise ValueError(
                f'expected an object {{"version": {VERSION}, "actions": {{...}}}}, got {type(data).__name__}'
            )
        for key in data:
            if key not in FILE_KEYS:
                raise ValueError(f"unknown key {key!r}{_close(key, FILE_KEYS)}; keys: {', '.join(FILE_KEYS)}")
        version = data.get("version")
        if type(version) is not int or version != VERSION:  # true == 1 and 1.0 == 1 in Python
            raise ValueError(f"version {repr(version)[:40]} is not {VERSION}")
        dead_zone = data.get("dead_zone")
        ok = isinstance(dead_zone, int | float) and not isinstance(dead_zone, bool) and 0.0 <= dead_zone < 1.0
        if dead_zone is not None and not (ok and math.isfinite(dead_zone)):
            raise ValueError(f"dead_zone must be a number from 0 up to (not including) 1, not {dead_zone!r}")
        given = data.get("actions", {})
        if not isinstance(given, dict):
            raise ValueError('"actions" must be an object: {"action": ["binding", ...]}')
        trial = ActionMap(input=self.input)
        trial.kinds = dict(self.kinds)
        for action, inputs in given.items():
            if action not in self.bindings:
                raise ValueError(f"unknown action {action!r}{_close(action, self.bindings)}")
            if not isinstance(inputs, list):
                raise ValueError(f"action {action!r}: expected a list of bindings, got {repr(inputs)[:80]}")
            try:
                trial.bind(action, *inputs)
            except ValueError as exc:
                named = repr(action) in str(exc)  # "'turn' is an axis action: ..." says which already
                raise ValueError(str(exc) if named else f"action {action!r}: {exc}") from None
        self.bindings.update(trial.bindings)
        if dead_zone is not None:
            self.dead_zone = float(dead_zone)
