"""Levels of detail built in a child process, for windowed sessions: the window keeps drawing (the
mesh at full detail) while a big model's levels are made, and they are swapped in when ready.

Why a process, not a thread of the job pool: fast-simplification holds the GIL for each whole
simplification (about a second a level at 263k vertices on the 2-core box), so a thread still
stalled the frame loop: measured with a build in a thread, the main thread's longest wait was
2.2 s at 66k vertices and 2.8 s at 263k, 5.5 and 8.7 s in all; with this child, 0.25-0.33 s on
the same busy box (0.08 s with no build at all). The child costs about 2 s to start, once, on the
first big mesh, and a copy of the mesh each way.

Why `python -m` and pipes, not multiprocessing: its spawn and forkserver start methods import the
parent's main module in the child, and a game script with no `if __name__ == "__main__"` guard
would open a second window there; a fork would copy the Vulkan device and held locks.

Headless runs (tests, screenshots, benchmarks) build on the calling thread instead, so a frame's
image does not depend on when a build finished (mesh_registry.py)."""

from __future__ import annotations

import dataclasses
import os
import pickle
import queue
import subprocess
import sys
import threading
from typing import Any, BinaryIO

import numpy as np

from ..layouts import MAX_LODS
from .mesh_data import MeshData
from .mesh_lod import Lod, build_lods

__all__ = ["LevelBuilder"]


def _received(lods: list[Lod]) -> list[Lod]:
    """Levels as they come back: MeshData's arrays made read-only again (pickling drops that; they
    own their memory, so no copy is needed, unlike going through MeshData's constructor)."""
    for lod in lods:
        for field in dataclasses.fields(lod.mesh):
            value = getattr(lod.mesh, field.name)
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
    return lods


class LevelBuilder:
    """One child process, started on the first submit; builds run one at a time, in order. Two
    threads, blocked on the pipes without the GIL, send the meshes (a pipe holds 64 KB: writing
    from the caller waited 1.5 s for the child to start reading) and file the results."""

    def __init__(self) -> None:
        self._child: subprocess.Popen[bytes] | None = None
        self._outbox: queue.SimpleQueue[tuple[int, MeshData] | None] = queue.SimpleQueue()
        self._pending: set[int] = set()
        self._done: dict[int, tuple[list[Lod] | None, str | None]] = {}
        self._arrived = threading.Condition()

    def submit(self, key: int, mesh: MeshData) -> None:
        if key in self._pending:
            return
        if self._child is None:
            self._child = subprocess.Popen(
                [sys.executable, "-m", __name__], stdin=subprocess.PIPE, stdout=subprocess.PIPE
            )
            threading.Thread(target=self._read, args=(self._child.stdout,), name="lod-results", daemon=True).start()
            threading.Thread(target=self._send, args=(self._child.stdin,), name="lod-meshes", daemon=True).start()
        self._pending.add(key)
        self._outbox.put((key, mesh))

    def pending(self, key: int) -> bool:
        return key in self._pending

    def finished(self) -> list[tuple[int, list[Lod]]]:
        """The builds done since the last call (without waiting); a build that failed raises here."""
        with self._arrived:
            done = list(self._done)
        return [(key, self.wait(key)) for key in done]

    def wait(self, key: int) -> list[Lod]:
        with self._arrived:
            self._arrived.wait_for(lambda: key in self._done)
            lods, error = self._done.pop(key)
        self._pending.discard(key)
        if lods is None:
            raise RuntimeError(f"building levels of detail in the background failed: {error}")
        return _received(lods)

    def _send(self, requests: BinaryIO) -> None:
        while (item := self._outbox.get()) is not None:
            try:
                pickle.dump(item, requests, protocol=pickle.HIGHEST_PROTOCOL)
                requests.flush()
            except OSError:  # the child ended; the reader fails what is pending
                return
        requests.close()

    def _read(self, results: BinaryIO) -> None:
        while True:
            try:
                key, lods, error = pickle.load(results)
            except (EOFError, OSError, pickle.UnpicklingError):  # the child ended: fail what is left
                with self._arrived:
                    for key in self._pending - set(self._done):
                        self._done[key] = (None, "the child process ended")
                    self._arrived.notify_all()
                return
            with self._arrived:
                self._done[key] = (lods, error)
                self._arrived.notify_all()

    def close(self) -> None:
        """End the child: builds under way or queued are dropped."""
        child, self._child = self._child, None
        if child is not None:
            self._outbox.put(None)
            child.terminate()
            child.wait()
        self._pending.clear()
        self._done.clear()


def _serve(requests: BinaryIO, results: BinaryIO) -> None:
    """The child's loop: (key, mesh) in, (key, levels or None, error or None) out, until EOF."""
    while True:
        try:
            key, mesh = pickle.load(requests)
        except EOFError:
            return
        reply: tuple[Any, ...]
        try:
            reply = (key, build_lods(mesh)[:MAX_LODS], None)
        except Exception as exc:  # sent back, raised by the parent's wait
            reply = (key, None, f"{type(exc).__name__}: {exc}")
        pickle.dump(reply, results, protocol=pickle.HIGHEST_PROTOCOL)
        results.flush()


if __name__ == "__main__":
    # results on a private copy of stdout; anything else printing to stdout goes to stderr
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    _serve(sys.stdin.buffer, out)
