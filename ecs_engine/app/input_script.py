"""Input scripts: key presses by frame, replayed into a run (`--input-script PATH`) or recorded
from one (`--record-input PATH`), so a game can be tested and replayed headless.

The format is text, one event a line: the frame (0-based, ascending), the action and the key,
`#` starting a comment:

    # frame action key
    10 down w
    10 down space
    70 up space
    130 up w

Keys are the names the InputState resource uses: GLFW's key names in lower case without KEY_
(`left_shift`, `f12`, `space`) and `mouse_left`, `mouse_right`, `mouse_middle`. Events of frame
N are applied before frame N's systems run. A recording writes, for each frame, the keys that
went down or up since the frame before, in this format, so replaying a recording gives the same
held keys and the same presses and releases frame by frame. A bad script (an unknown key
or action, a frame out of order, a line that is not three words) is one UsageError naming the
file and the line, before the run starts.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import UsageError
from ..systems.camera_control import InputState

ACTIONS = ("down", "up")


@dataclass
class InputScript:
    events: dict[int, list[tuple[str, str]]] = field(default_factory=dict)  # frame -> (action, key)

    def apply(self, frame: int, state: InputState) -> None:
        """This frame's events into the input state (held keys and this frame's edges)."""
        for action, key in self.events.get(frame, ()):
            if action == "down":
                state.press(key)
            else:
                state.release(key)


def read_script(path: str | os.PathLike[str]) -> InputScript:
    file = Path(path)
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"input script {file}: cannot be read ({exc})") from None
    script, last = InputScript(), -1
    for number, line in enumerate(text.splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        where = f"input script {file}, line {number}"
        if len(words) != 3:
            raise UsageError(f"{where}: expected 'FRAME down|up KEY', got {line.strip()!r}")
        frame_text, action, key = words
        try:
            frame = int(frame_text)
        except ValueError:
            raise UsageError(f"{where}: the frame {frame_text!r} is not a whole number") from None
        if frame < 0 or frame < last:
            raise UsageError(f"{where}: frame {frame} comes before frame {last} (frames must not go back)")
        if action not in ACTIONS:
            raise UsageError(f"{where}: unknown action {action!r}; actions: {', '.join(ACTIONS)}")
        try:
            InputState.check(key)
        except ValueError as exc:
            raise UsageError(f"{where}: {exc}") from None
        script.events.setdefault(frame, []).append((action, key))
        last = frame
    return script


class InputRecorder:
    """Writes each frame's presses and releases, in the script format."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.lines = ["# recorded by ecs-engine --record-input: frame action key"]

    def frame(self, frame: int, state: InputState) -> None:
        for key in sorted(state.just_pressed | state.just_released):
            down, up = key in state.just_pressed, key in state.just_released
            # both: released then pressed again if it is held now, else pressed then released
            order = ("up", "down") if key in state.pressed else ("down", "up")
            for action in order:
                if (action == "down" and down) or (action == "up" and up):
                    self.lines.append(f"{frame} {action} {key}")

    def write(self) -> None:
        try:
            self.path.write_text("\n".join(self.lines) + "\n", encoding="utf-8")
        except OSError as exc:
            raise UsageError(f"input recording {self.path}: cannot be written ({exc})") from None
