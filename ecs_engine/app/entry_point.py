"""How every command-line entry point ends when it is stopped from outside (`ecs-engine`,
`python -m ecs_engine`, `ecs-engine bench`, `python -m ecs_engine.bench`).

Ctrl-C is one line and exit 130, whenever it comes (imports of vulkan, numba or imgui take
seconds, device creation and the first frame's compiles more), never a KeyboardInterrupt
traceback. A reader of stdout that goes away (`| head`) ends the command quietly, as it ends
`ls` or `git log`: no traceback, no "Broken pipe" error, and no second complaint from the
interpreter's own flush of stdout at exit.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable

INTERRUPTED = 130  # 128 + SIGINT: what a shell reports for a program stopped by Ctrl-C
CLOSED_PIPE = 141  # 128 + SIGPIPE: what a shell reports for `yes | head`


def run_command(prog: str, body: Callable[[], int]) -> int:
    """`body()`'s exit status, or INTERRUPTED after one line on Ctrl-C, or CLOSED_PIPE, silently,
    when stdout's reader has gone."""
    try:
        return body()
    except KeyboardInterrupt:
        return interrupted(prog)
    except BrokenPipeError:
        return closed_pipe()


def interrupted(prog: str) -> int:
    try:
        print(f"{prog}: interrupted", file=sys.stderr)
    except (OSError, ValueError):  # stderr closed too: the exit status says it
        pass
    return INTERRUPTED


def closed_pipe() -> int:
    """stdout is pointed at the null device: what is still buffered for it (and the interpreter's
    flush at exit) goes nowhere instead of raising BrokenPipeError again."""
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
    except (OSError, ValueError, AttributeError):  # no real stdout (embedded, pytest's capture)
        pass
    return CLOSED_PIPE
