"""Input scripts: key presses by frame, replayed into a run (`--input-script PATH`) or recorded
from one (`--record-input PATH`), so a game can be tested and replayed headless.

The format is text, one event a line: the frame (0-based, ascending), the action and the key,
`#` starting a comment:

    # frame action key
    10 down w
    10 down space
    70 up space
    130 up w

Keys are the names the InputState resource uses (systems.camera_control.KEYS plus the games'
`space` and `r`). Events of frame N are applied before frame N's systems run. A recording
writes, for each frame, the keys that went down or up since the frame before, in this format,
so replaying a recording gives the same key states frame by frame. A bad script (an unknown key
or action, a frame out of order, a line that is not three words) is one UsageError naming the
file and the line, before the run starts.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import UsageError
from ..systems.camera_control import KEYS as FLY_KEYS

KEYS = FLY_KEYS | {"space", "r"}  # what window.KEY_NAMES gives (a test keeps the two equal)
ACTIONS = ("down", "up")


@dataclass
class InputScript:
    events: dict[int, list[tuple[str, str]]] = field(default_factory=dict)  # frame -> (action, key)

    def apply(self, frame: int, pressed: set[str]) -> None:
        """This frame's events into the held keys."""
        for action, key in self.events.get(frame, ()):
            if action == "down":
                pressed.add(key)
            else:
                pressed.discard(key)


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
        if key not in KEYS:
            raise UsageError(f"{where}: unknown key {key!r}; keys: {', '.join(sorted(KEYS))}")
        script.events.setdefault(frame, []).append((action, key))
        last = frame
    return script


class InputRecorder:
    """Writes what changed in the held keys each frame, in the script format."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.lines = ["# recorded by ecs-engine --record-input: frame action key"]
        self.previous: set[str] = set()

    def frame(self, frame: int, pressed: set[str]) -> None:
        for key in sorted(pressed - self.previous):
            self.lines.append(f"{frame} down {key}")
        for key in sorted(self.previous - pressed):
            self.lines.append(f"{frame} up {key}")
        self.previous = set(pressed)

    def write(self) -> None:
        try:
            self.path.write_text("\n".join(self.lines) + "\n", encoding="utf-8")
        except OSError as exc:
            raise UsageError(f"input recording {self.path}: cannot be written ({exc})") from None
