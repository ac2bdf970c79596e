"""`FileWatch`: which of a few files changed on disk, by polling their stat.

Why polling and not a watcher library (watchfiles, watchdog): hot reload watches a handful of
files (a game's source, the images and models it loaded, the engine's shaders) and acts only at
a frame boundary on the main thread, so a notification thread would only set a flag that the
frame loop reads anyway. A few `os.stat` calls every `interval` seconds cost microseconds, need
no dependency, and behave the same on Linux, macOS, Windows and network drives, where inotify
and FSEvents differ or miss events. A file's stamp is its mtime, size and inode: editors that
save by writing a new file and renaming it over the old one change the inode even when the
mtime's resolution hides the write.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable
from pathlib import Path

Stamp = tuple[int, int, int] | None  # (mtime_ns, size, inode), None: no such file now

POLL_INTERVAL_S = 0.25  # at most this often: a change shows within a second with room to spare


def stamp_of(path: Path) -> Stamp:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_mtime_ns, st.st_size, st.st_ino)


class FileWatch:
    """The files given to `watch`; `changed()` lists those whose stamp differs from the last one
    seen. A file that is missing (mid-save, or deleted) is not a change: it is seen when it is
    back, if it differs then."""

    def __init__(self, interval: float = POLL_INTERVAL_S, clock: Callable[[], float] = time.monotonic) -> None:
        self.interval = interval
        self.clock = clock
        self._stamps: dict[Path, Stamp] = {}
        self._next = 0.0

    def watch(self, paths: Iterable[str | os.PathLike[str]]) -> None:
        """Watch `paths` from their state now (one already watched keeps its last stamp)."""
        for path in paths:
            resolved = Path(path).resolve()
            if resolved not in self._stamps:
                self._stamps[resolved] = stamp_of(resolved)

    def forget(self, path: str | os.PathLike[str]) -> None:
        self._stamps.pop(Path(path).resolve(), None)

    @property
    def paths(self) -> list[Path]:
        return list(self._stamps)

    def changed(self) -> list[Path]:
        """The watched files changed since the last call (none before `interval` has passed)."""
        now = self.clock()
        if now < self._next:
            return []
        self._next = now + self.interval
        found = []
        for path, seen in self._stamps.items():
            current = stamp_of(path)
            if current is not None and current != seen:
                self._stamps[path] = current
                found.append(path)
        return found
