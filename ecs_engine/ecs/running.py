"""What each thread is running in a world (the parallel schedule runs several systems at once)."""

from __future__ import annotations

import threading
from typing import Any

from .commands import CommandQueue


class Running(threading.local):
    """Per thread: the system it runs (the parallel schedule runs several at once), its change
    tick, the query loops open, and the command queue of a system run in parallel (merged into
    the world's in the schedule's declared order after the group)."""

    system: Any = None  # the world's RunningSystem
    tick: int = 0
    iter_depth: int = 0
    commands: CommandQueue | None = None
