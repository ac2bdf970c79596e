"""Streamed clips: a long file (music) decoded a little at a time on a thread of its own rather
than held whole in memory (three minutes of stereo at 48 kHz are 69 MB as float32).

Each voice playing a streamed clip has its own `Stream`: a decoder (miniaudio's, to stereo at
the mixer's rate) that keeps up to `AHEAD_S` seconds decoded ahead of what the mixer has taken.
A looping stream opens its file again at the end. The mixer takes a block at a time (`read`):
on a sound device it never waits, and a stream that has fallen behind gives silence for the rest
of that block (counted in `late`); for a capture it waits for the decoder, so the file it
writes is the same every run."""

from __future__ import annotations

import os
import threading
from collections import deque

import numpy as np

from ..errors import UsageError
from .clips import FORMATS
from .library import load

AHEAD_S = 1.0  # seconds kept decoded ahead of the mixer
CHUNK = 4096  # frames decoded at a time


class Stream:
    """One voice's decoder of `path` (see the module)."""

    def __init__(self, path: str, rate: int, loop: bool) -> None:
        self.path, self.rate, self.loop = path, rate, loop
        self._chunks: deque[np.ndarray] = deque()
        self._buffered = 0  # frames in _chunks
        self._offset = 0  # frames of _chunks[0] already taken
        self._cond = threading.Condition()
        self._done = False  # the decoder reached the end (and does not loop)
        self._closed = False
        self.error: str | None = None
        self.late = 0  # blocks a device output asked for before they were decoded
        self._thread = threading.Thread(target=self._decode, name=f"stream {path}", daemon=True)
        self._thread.start()

    def _decode(self) -> None:
        miniaudio = load()
        limit = int(AHEAD_S * self.rate)
        try:
            while not self._closed:
                frames = miniaudio.stream_file(self.path, miniaudio.SampleFormat.FLOAT32, 2, self.rate, CHUNK)
                for chunk in frames:
                    block = np.frombuffer(chunk, np.float32).reshape(-1, 2)
                    with self._cond:
                        while self._buffered >= limit and not self._closed:
                            self._cond.wait()
                        if self._closed:
                            return
                        self._chunks.append(block)
                        self._buffered += len(block)
                        self._cond.notify_all()
                if not self.loop:
                    break
        except (miniaudio.DecodeError, miniaudio.MiniaudioError, OSError) as error:
            self.error = f"sound file {self.path}: {error}"
        with self._cond:
            self._done = True
            self._cond.notify_all()

    def read(self, frames: int, wait: bool) -> tuple[np.ndarray, bool]:
        """The next `frames` (frames, 2), and whether the stream has ended (no more to come).
        `wait`: block until they are decoded (a capture), else silence where they are not."""
        out = np.zeros((frames, 2), np.float32)
        got = 0
        with self._cond:
            while got < frames:
                if not self._chunks:
                    if self._done:
                        break
                    if not wait:
                        self.late += 1
                        break
                    self._cond.wait()
                    continue
                head = self._chunks[0]
                take = min(frames - got, len(head) - self._offset)
                out[got : got + take] = head[self._offset : self._offset + take]
                got += take
                self._offset += take
                self._buffered -= take
                if self._offset == len(head):
                    self._chunks.popleft()
                    self._offset = 0
            self._cond.notify_all()
            ended = self._done and not self._chunks
        return out, ended

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()


def check_streamable(path: str) -> None:
    """UsageError in one line unless miniaudio can open `path` to stream it (checked when the
    clip is made, not when a voice first plays it)."""
    miniaudio = load()
    if not os.path.isfile(path):
        raise UsageError(f"sound file {path}: no such file")
    try:
        info = miniaudio.get_file_info(path)
    except (miniaudio.DecodeError, miniaudio.MiniaudioError) as error:
        raise UsageError(f"sound file {path}: not a {FORMATS} file miniaudio can decode ({error})") from None
    if info.num_frames == 0:
        raise UsageError(f"sound file {path}: it holds no samples")
