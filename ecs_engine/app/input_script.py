"""Input scripts: keys, buttons, gamepad axes and the mouse by frame, replayed into a run
(`--input-script PATH`) or recorded from one (`--record-input PATH`), so a game can be tested and
replayed headless.

The format is text, one event a line: the frame (0-based, ascending), the action and its
arguments, `#` starting a comment:

    # frame action arguments
    10 down w                    # a key, mouse button or gamepad button goes down ...
    10 down gamepad_a
    70 up gamepad_a              # ... or up
    80 axis gamepad_left_x -0.5  # a gamepad axis' raw value, -1..1 (triggers 0..1)
    90 move 412.5 120            # the mouse pointer, pixels from the top left of the view
    95 scroll 0 -1               # the wheel
    100 text "level 2.scene"     # text typed (one JSON string)
    130 up w
    131 dt 0.0213                # the frame's step in seconds (a window's recording writes one a frame)

A script sets how its run steps, in a window as headless, so that it plays the same in both. A
script without `dt` lines steps as a headless run: 1/60 s a frame, one fixed step. A recording
made in a window writes each frame's `dt` (its frames take what they take), and a script with
`dt` lines steps as a window does: each frame its `dt` (1/60 s where a frame has none), fixed
steps of 1/120 s, the per-frame stages' step at most 0.1 s; so a window's recording replays
exactly, in a window or headless. A `dt` is from 1e-6 to 10 seconds.

Names are the InputState resource's (ecs_engine.systems.input_state): GLFW's key names in lower
case without KEY_ (`left_shift`, `f12`, `space`), `mouse_left`, `mouse_right`, `mouse_middle`,
the gamepad buttons `gamepad_a` ... `gamepad_dpad_left` and the axes `gamepad_left_x` ...
`gamepad_right_trigger` (a script's gamepad is every gamepad at once, as the names are).
Events of frame N are applied before frame N's systems run; in a headless run the mouse is in
the offscreen image's pixels (--width x --height). In the editor or a game's HUD they reach ImGui
too (app/imgui_input.py), so a script clicks buttons and menus, types into fields and presses
shortcuts; a key down is a key, not a character (as on a keyboard, where GLFW reports both):
`text` types. A recording writes, for each frame, the keys
and buttons that went down or up since the frame before, the axes that changed, where the mouse
ended up if it moved, the scroll and the text typed, in this format, so replaying a recording gives the same
input frame by frame. Scripts of only `down` and `up` lines (the first version of the format)
read as before. A bad script (an unknown name or action, a frame out of order, a value that is
not a finite number, a line with the wrong number of words) is one UsageError naming the file
and the line, before the run starts; so is a script that is not a regular file (a FIFO such as
/dev/stdin under a pipe) or is over 16 MiB (ecs_engine/user_files.py).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..ecs.timestep import FixedTimestep
from ..errors import UsageError
from ..systems.input_state import InputState
from ..user_files import INPUT_SCRIPT, UserFileError, read_user_file
from .settings import FIXED_DT, MAX_DT, SIM_STEP

# action -> the words after it
ACTIONS = {
    "down": ("KEY",),
    "up": ("KEY",),
    "axis": ("AXIS", "VALUE"),
    "move": ("X", "Y"),
    "scroll": ("DX", "DY"),
    "text": ("TEXT",),
    "dt": ("SECONDS",),
}
MIN_DT, MAX_SCRIPT_DT = 1e-6, 10.0  # a script's frame step: bounded, so a file cannot ask for a million fixed steps


@dataclass
class InputScript:
    events: dict[int, list[tuple[str, ...]]] = field(default_factory=dict)  # frame -> (action, *arguments)
    steps: dict[int, float] = field(default_factory=dict)  # frame -> its dt line's seconds

    def step(self, frame: int) -> tuple[float, float]:
        """(dt, the per-frame stages' bound) of `frame` in a run this script drives: its `dt`
        line's (else 1/60 s), bounded as a window bounds it when the script has `dt` lines (a
        window's recording), else as a headless run does."""
        return self.steps.get(frame, FIXED_DT), (MAX_DT if self.steps else FIXED_DT)

    def clock(self) -> FixedTimestep:
        """The fixed-step clock of a run this script drives: a window's (1/120 s steps) for a
        script with `dt` lines, a headless run's (one 1/60 s step a frame) for one without."""
        return FixedTimestep(SIM_STEP if self.steps else FIXED_DT)

    def apply(self, frame: int, state: InputState) -> None:
        """This frame's events into the input state (held keys, axes, mouse and this frame's edges)."""
        for action, *args in self.events.get(frame, ()):
            if action == "dt":
                continue  # the loop asks step()
            if action == "down":
                state.press(args[0])
            elif action == "up":
                state.release(args[0])
            elif action == "axis":
                state.set_axis(args[0], float(args[1]))
            elif action == "move":
                state.move_mouse(float(args[0]), float(args[1]))
            elif action == "text":
                state.text += args[0]
            else:
                state.scroll = (state.scroll[0] + float(args[0]), state.scroll[1] + float(args[1]))


def _usage(action: str) -> str:
    words = '"TEXT"' if action == "text" else " ".join(ACTIONS[action])
    return f"FRAME {'down|up' if action in ('down', 'up') else action} {words}"


def _text(rest: str) -> str:
    """The JSON string of a `text` line and nothing after it but a comment; ValueError if not."""
    try:
        text, end = json.JSONDecoder().raw_decode(rest)
    except json.JSONDecodeError:
        text, end = None, 0
    after = rest[end:].strip()
    if not isinstance(text, str) or (after and not after.startswith("#")):
        raise ValueError('text is one JSON string in double quotes, e.g. "Hello, world"')
    return text


def _check_event(action: str, args: list[str]) -> None:
    """A ValueError for an unknown name or a value that is not a finite number."""
    names = ACTIONS[action]
    for word, value in zip(names, args):
        if word == "KEY":
            InputState.check(value)
        elif word == "AXIS":
            InputState.check_axis(value)
        elif word != "TEXT":  # text was read as a JSON string: any is fine
            try:
                number = float(value)
            except ValueError:
                number = math.nan
            if not math.isfinite(number):
                raise ValueError(f"{word} {value!r} is not a finite number")
            if word == "VALUE" and abs(number) > 1.0:
                raise ValueError(f"an axis value is from -1 to 1, not {value}")
            if word == "SECONDS" and not MIN_DT <= number <= MAX_SCRIPT_DT:
                raise ValueError(f"a frame's dt is from {MIN_DT:g} to {MAX_SCRIPT_DT:g} seconds, not {value}")


def read_script(path: str | os.PathLike[str]) -> InputScript:
    file = Path(path)
    try:
        text = read_user_file(file, INPUT_SCRIPT).decode("utf-8")
    except UserFileError as exc:  # a FIFO, a device, or too large
        raise UsageError(f"input script {file}: {exc.why}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"input script {file}: cannot be read ({exc})") from None
    script, last = InputScript(), -1
    for number, line in enumerate(text.splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        where = f"input script {file}, line {number}"
        head = line.split(None, 2)
        if len(head) >= 2 and head[1] == "text":  # the rest is a JSON string, which may hold a #
            try:
                words = [head[0], "text", _text(head[2] if len(head) > 2 else "")]
            except ValueError as exc:
                raise UsageError(f"{where}: {exc}; got {line.strip()!r}") from None
        if len(words) < 2:
            usage = ", ".join(_usage(a) for a in ("down", "axis", "move", "scroll", "text"))
            raise UsageError(f"{where}: expected one of {usage}; got {line.strip()!r}")
        frame_text, action, *args = words
        try:
            frame = int(frame_text)
        except ValueError:
            raise UsageError(f"{where}: the frame {frame_text!r} is not a whole number") from None
        if frame < 0 or frame < last:
            raise UsageError(f"{where}: frame {frame} comes before frame {last} (frames must not go back)")
        if action not in ACTIONS:
            raise UsageError(f"{where}: unknown action {action!r}; actions: {', '.join(ACTIONS)}")
        if len(args) != len(ACTIONS[action]):
            raise UsageError(f"{where}: expected '{_usage(action)}', got {line.strip()!r}")
        try:
            _check_event(action, args)
        except ValueError as exc:
            raise UsageError(f"{where}: {exc}") from None
        if action == "dt" and frame in script.steps:
            raise UsageError(f"{where}: frame {frame} has a dt already")
        script.events.setdefault(frame, []).append((action, *args))
        if action == "dt":
            script.steps[frame] = float(args[0])
        last = frame
    return script


class InputRecorder:
    """Writes each frame's presses and releases, in the script format."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.lines = ["# recorded by ecs-engine --record-input: frame action arguments"]
        self.mouse = (0.0, 0.0)  # a new InputState's
        self.axes: dict[str, float] = {}

    def frame(self, frame: int, state: InputState, dt: float = FIXED_DT) -> None:
        if dt != FIXED_DT:  # a window's frame: its step, so that a replay steps the same
            self.lines.append(f"{frame} dt {dt!r}")
        if state.mouse != self.mouse:
            self.mouse = state.mouse
            self.lines.append(f"{frame} move {state.mouse[0]!r} {state.mouse[1]!r}")
        for name, value in sorted(state.axes.items()):
            if value != self.axes.get(name, 0.0):
                self.lines.append(f"{frame} axis {name} {value!r}")
        self.axes = dict(state.axes)
        if state.scroll != (0.0, 0.0):
            self.lines.append(f"{frame} scroll {state.scroll[0]!r} {state.scroll[1]!r}")
        text = f"{frame} text {json.dumps(state.text, ensure_ascii=False)}" if state.text else None
        for key in sorted(state.just_pressed | state.just_released):
            down, up = key in state.just_pressed, key in state.just_released
            # both: released then pressed again if it is held now, else pressed then released
            order = ("up", "down") if key in state.pressed else ("down", "up")
            for action in order:
                if (action == "down" and down) or (action == "up" and up):
                    self.lines.append(f"{frame} {action} {key}")
        if text is not None:  # after its keys, as GLFW reports a character after its key
            self.lines.append(text)

    def write(self) -> None:
        try:
            self.path.write_text("\n".join(self.lines) + "\n", encoding="utf-8")
        except OSError as exc:
            raise UsageError(f"input recording {self.path}: cannot be written ({exc})") from None
