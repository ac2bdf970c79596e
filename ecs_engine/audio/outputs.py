"""Where the mixed sound goes.

- `DeviceOutput`: the sound card, through miniaudio. Its own thread asks for each block and the
  mixer makes it there, so the frame only hands over parameters. With no sound device (a server,
  CI, the GPU host) it falls back to miniaudio's null backend, which consumes sound in real time
  and plays nothing, and says so in one line.
- `CaptureOutput`: a WAV file (32-bit float, stereo) of exactly what would have been played,
  made frame by frame: after each frame, the samples up to that frame's time are mixed and
  written, so the same run (a replayed input script) writes the same file.
"""

from __future__ import annotations

import contextlib
import os
import struct
import sys
import time
from collections.abc import Generator, Iterator
from pathlib import Path
from typing import BinaryIO

import numpy as np

from ..errors import UsageError
from .library import load
from .mixer import Mixer

BUFFER_MS = 40  # the device's buffer: what a frame may overrun before the sound gaps
_SLACK = 0.002  # s: a block asked for this late after the last one ran out is the device's jitter, not a gap


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """The C libraries' own chatter (ALSA lists every card it fails to open) kept off the console:
    the engine says in one line what came of it."""
    try:
        saved = os.dup(2)
    except OSError:
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            sys.stderr.flush()
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


class DeviceOutput:
    """The mixer played on the default sound device, or on the null backend (`null=True`, or when
    no device opens: `fallback` then says why)."""

    def __init__(self, mixer: Mixer, null: bool = False, buffer_ms: int = BUFFER_MS) -> None:
        miniaudio = load()
        self.mixer = mixer
        self.fallback: str | None = None
        self.underruns = 0  # blocks asked for after the sound handed over before had run out: a gap
        self.error: str | None = None  # the mixer's failure, if it failed (the sound then goes silent)
        self.buffer_seconds = buffer_ms / 1000.0
        self._runs_out: float | None = None  # when the sound handed over so far ends playing
        kwargs = dict(
            output_format=miniaudio.SampleFormat.FLOAT32,
            nchannels=2,
            sample_rate=mixer.sample_rate,
            buffersize_msec=buffer_ms,
            app_name="ecs_engine",
        )
        device = None
        if not null:
            try:
                with _quiet_stderr():
                    device = miniaudio.PlaybackDevice(**kwargs)
            except miniaudio.MiniaudioError as error:
                self.fallback = (
                    f"no sound device ({error.args[0] if error.args else error}): sound goes to the null output"
                )
        if device is None:
            try:
                device = miniaudio.PlaybackDevice(**kwargs, backends=[miniaudio.Backend.NULL])
            except miniaudio.MiniaudioError as error:
                raise UsageError(f"sound: the null output does not open either ({error})") from None
        self.device = device
        self.backend = str(getattr(device, "backend", "?"))
        if self.backend == "Null" and self.fallback is None and not null:  # miniaudio's own last resort
            self.fallback = "no sound device (no audio system answered): sound goes to the null output"
        feed = self._feed()
        next(feed)
        device.start(feed)

    def _feed(self) -> Generator[bytes, int, None]:
        frames = yield b""
        while True:
            now = time.perf_counter()
            if self._runs_out is not None and now > self._runs_out + _SLACK:
                self.underruns += 1
            start = now if self._runs_out is None else max(now, self._runs_out)
            self._runs_out = start + frames / self.mixer.sample_rate
            if self.error is None:
                try:
                    block = self.mixer.render(frames)
                except Exception as error:  # the sound thread must not die: silence, and the reason kept
                    self.error = f"{type(error).__name__}: {error}"
                    block = np.zeros((frames, 2), np.float32)
            else:
                block = np.zeros((frames, 2), np.float32)
            frames = yield block.tobytes()

    def advance(self, seconds: float) -> None:
        """Nothing: the device's thread asks for sound at its own pace."""

    def close(self) -> None:
        self.device.close()


class CaptureOutput:
    """The mixed sound written to `path` (see the module); `advance(seconds)` after each frame."""

    def __init__(self, mixer: Mixer, path: str | os.PathLike[str]) -> None:
        self.mixer = mixer
        self.path = Path(path)
        self.fallback: str | None = None
        self.underruns = 0
        self.error: str | None = None
        self.backend = "capture"
        self._seconds = 0.0
        self._written = 0
        try:
            self._file: BinaryIO | None = open(self.path, "wb")
        except OSError as error:
            raise UsageError(f"--audio-out {self.path}: cannot be written ({error.strerror or error})") from None
        self._file.write(_wav_header(0, mixer.sample_rate))

    def advance(self, seconds: float) -> None:
        """Mix and write the sound up to the run's time plus `seconds` (a frame's dt)."""
        self._seconds += seconds
        due = round(self._seconds * self.mixer.sample_rate) - self._written
        if due <= 0 or self._file is None:
            return
        block = self.mixer.render(due)
        self._file.write(block.astype("<f4").tobytes())
        self._written += due

    @property
    def frames_written(self) -> int:
        return self._written

    def close(self) -> None:
        if self._file is None:
            return
        self._file.seek(0)
        self._file.write(_wav_header(self._written, self.mixer.sample_rate))
        self._file.close()
        self._file = None


def _wav_header(frames: int, rate: int, channels: int = 2) -> bytes:
    """A RIFF/WAVE header for `frames` of 32-bit float samples (format 3, IEEE float)."""
    data = frames * channels * 4
    fmt = struct.pack("<HHIIHH", 3, channels, rate, rate * channels * 4, channels * 4, 32)
    return (
        b"RIFF"
        + struct.pack("<I", 4 + 8 + len(fmt) + 8 + data)
        + b"WAVE"
        + b"fmt "
        + struct.pack("<I", len(fmt))
        + fmt
        + b"data"
        + struct.pack("<I", data)
    )


def read_wav(path: str | os.PathLike[str]) -> tuple[np.ndarray, int]:
    """A WAV file that CaptureOutput wrote: (frames, 2) float32 samples and the rate."""
    raw = Path(path).read_bytes()
    if raw[:4] != b"RIFF" or raw[8:12] != b"WAVE":
        raise UsageError(f"{path}: not a WAV file")
    channels, rate = struct.unpack("<HI", raw[22:28])
    at = raw.find(b"data", 12)
    (size,) = struct.unpack("<I", raw[at + 4 : at + 8])
    return np.frombuffer(raw[at + 8 : at + 8 + size], "<f4").reshape(-1, channels), rate
