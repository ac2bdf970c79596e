"""The mixer: clips, voices and buses, mixed one block at a time by whoever asks for sound (the
sound device's thread, or the frame itself when the sound is captured to a file).

The frame never touches a voice. It queues commands (start, stop, pause, new gains and rates,
bus volumes, the limiter's settings) under a short lock; the mixer takes the whole queue at the
head of its next block and applies it there, so a slow frame only means a block mixed with the
last parameters, never a gap in the sound. Voices that end (a clip that does not loop) are
handed back the same way (`finished`)."""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from .limiter import Limiter, limit_block
from .mix_kernel import mix_block
from .streams import Stream

SAMPLE_RATE = 48_000


@dataclass(frozen=True)
class ClipBank:
    """Every clip's samples in one array (what the kernel reads), with each clip's place."""

    samples: np.ndarray
    offset: np.ndarray
    length: np.ndarray
    channels: np.ndarray
    rate: np.ndarray  # each clip's own sample rate

    @staticmethod
    def empty() -> ClipBank:
        no = np.zeros(0, np.int64)
        return ClipBank(np.zeros(1, np.float32), no, no, no, np.zeros(0, np.float64))

    def add(self, samples: np.ndarray, rate: int) -> ClipBank:
        frames, channels = samples.shape
        start = len(self.samples)
        return ClipBank(
            np.concatenate([self.samples, np.ascontiguousarray(samples, np.float32).reshape(-1)]),
            np.append(self.offset, start),
            np.append(self.length, frames),
            np.append(self.channels, channels),
            np.append(self.rate, float(rate)),
        )


class _Voices:
    """The mixer's voice table (the mixer thread's own), grown on demand."""

    def __init__(self, capacity: int = 64) -> None:
        self.clip = np.zeros(capacity, np.int64)
        self.position = np.zeros(capacity, np.float64)
        self.pitch = np.ones(capacity, np.float64)  # times the clip's rate over the output's
        self.gain = np.zeros((capacity, 2), np.float32)  # the voice's own (before its bus)
        self.gain_from = np.zeros((capacity, 2), np.float32)  # what the last block ended on (after the bus)
        self.loop = np.zeros(capacity, bool)
        self.live = np.zeros(capacity, bool)
        self.mono = np.zeros(capacity, bool)
        self.active = np.zeros(capacity, bool)  # started and not yet finished or stopped
        self.paused = np.zeros(capacity, bool)
        self.stopping = np.zeros(capacity, bool)
        self.bus = np.zeros(capacity, np.int64)
        self.stream = np.zeros(capacity, bool)  # plays a streamed clip (streams.py), not the bank

    def fit(self, voice: int) -> None:
        capacity = len(self.clip)
        if voice < capacity:
            return
        grown = max(voice + 1, 2 * capacity)
        for name, column in vars(self).items():
            wider = np.zeros((grown, *column.shape[1:]), column.dtype)
            wider[:capacity] = column
            setattr(self, name, wider)


def _warm_kernel() -> None:
    """Compile the kernels (or load them from numba's cache) on this thread, not the sound device's:
    there they would wait for the GIL at each step of loading while the frame holds it, and the
    sound would stop for as long as the frame runs Python (measured: the whole of a 0.5 s frame)."""
    one, i64, f64, yes = np.ones(1, np.int64), np.zeros(1, np.int64), np.zeros(1), np.ones(1, bool)
    gains = np.zeros((1, 2), np.float32)
    mix_block(np.zeros((2, 4), np.float32), np.zeros(4, np.float32), i64, one * 2, one, i64, f64, f64 + 1.0,
              gains, gains.copy(), yes, yes.copy(), ~yes)  # fmt: skip
    limit_block(np.ones((2, 4), np.float32), 0.5, 0.01, 1.0)


class Mixer:
    """Clips (`add_clip`), voices (`start`, `stop`, `pause`, `set`), buses (`set_buses`), and
    `render(frames)`: the next block of stereo float32 sound."""

    def __init__(self, sample_rate: int = SAMPLE_RATE) -> None:
        self.sample_rate = sample_rate
        self.bank = ClipBank.empty()
        self._voices = _Voices()
        self._queue: list[tuple[Any, ...]] = []
        self._lock = threading.Lock()
        self._finished: list[int] = []
        self._bus_gain = np.ones(1, np.float32)
        self._used = 0  # voices 0.._used-1 hold every active one
        self._stopping = 0  # voices fading out this block
        self.frames_mixed = 0  # output frames rendered so far
        self.mix_seconds = 0.0  # CPU time spent in render (the Perf line's audio figure)
        self.started_at: dict[int, float] = {}  # voice -> perf_counter of its start call, until first mixed
        self.latencies: deque[float] = deque(maxlen=4096)  # s from a start call to the block that mixed it
        self.streamed: dict[int, str] = {}  # clip -> the file its voices stream (streams.py)
        self._streams: dict[int, Stream] = {}  # voice -> its decoder
        self.wait_for_streams = False  # a capture waits for the decoders (the same file every run)
        self.limiter: Limiter | None = Limiter(sample_rate)  # the master's last step (limiter.py)
        _warm_kernel()

    # ---------------------------------------------------------------- the frame's side
    def add_clip(self, samples: np.ndarray, rate: int) -> int:
        """A clip's (frames, channels) float32 samples at `rate` Hz: its index."""
        with self._lock:
            self.bank = self.bank.add(samples, rate)
            return len(self.bank.length) - 1

    def add_stream(self, path: str) -> int:
        """A clip streamed from `path` when played (streams.py): its index. It holds one silent
        frame in the bank, so that clips keep one numbering."""
        with self._lock:
            self.bank = self.bank.add(np.zeros((1, 2), np.float32), self.sample_rate)
            clip = len(self.bank.length) - 1
            self.streamed[clip] = path
            return clip

    def start(
        self, voice: int, clip: int, gains: tuple[float, float], pitch: float, loop: bool, mono: bool, bus: int
    ) -> None:
        """Play `clip` on `voice` from its start."""
        with self._lock:
            self._queue.append(("start", voice, clip, gains, pitch, loop, mono, bus, time.perf_counter()))

    def stop(self, voice: int) -> None:
        """Fade `voice` out over the next block, then free it: reported in `finished` as an ended
        one is, so that the frame reuses it only once its fade is over."""
        with self._lock:
            self._queue.append(("stop", voice))

    def pause(self, voice: int, paused: bool) -> None:
        with self._lock:
            self._queue.append(("pause", voice, paused))

    def set(self, voices: np.ndarray, gains: np.ndarray, pitch: np.ndarray) -> None:
        """New gains ((k, 2): left, right, before the bus) and pitch factors for `voices`."""
        with self._lock:
            self._queue.append(("set", np.array(voices, np.int64), np.array(gains, np.float32), np.array(pitch)))

    def set_buses(self, gains: np.ndarray) -> None:
        """Each bus's gain, its parents' (the master's) already multiplied in."""
        with self._lock:
            self._queue.append(("buses", np.array(gains, np.float32)))

    def set_limiter(self, settings: tuple[float, float] | None) -> None:
        """The master limiter's (ceiling in dB, release in s), or None: off."""
        with self._lock:
            self._queue.append(("limiter", settings))

    def finished(self) -> list[int]:
        """The voices whose clips ended, or whose stop faded out, since the last call (they are
        free again)."""
        with self._lock:
            done, self._finished = self._finished, []
        return done

    # ---------------------------------------------------------------- the mixing side
    def _apply(self, commands: list[tuple[Any, ...]], now: float) -> None:
        v = self._voices
        for command in commands:
            kind = command[0]
            if kind == "set":
                voices, gains, pitch = command[1:]
                if len(voices):
                    v.fit(int(voices.max()))
                    v.gain[voices] = gains
                    v.pitch[voices] = pitch
            elif kind == "start":
                voice, clip, gains, pitch, loop, mono, bus, called = command[1:]
                v.fit(voice)
                self._used = max(self._used, voice + 1)
                if bus >= len(self._bus_gain):  # (the Audio resource sends a bus's gain before its first use)
                    self._bus_gain = np.r_[self._bus_gain, np.ones(bus + 1 - len(self._bus_gain), np.float32)]
                v.clip[voice], v.position[voice], v.pitch[voice] = clip, 0.0, pitch
                v.gain[voice] = gains
                v.gain_from[voice] = np.float32(gains) * self._bus_gain[bus]  # a sound starts at its level
                v.loop[voice], v.mono[voice], v.bus[voice] = loop, mono, bus
                v.live[voice] = v.active[voice] = True
                v.paused[voice] = v.stopping[voice] = False
                self.started_at[voice] = called
                self._close_stream(voice)
                v.stream[voice] = clip in self.streamed
                if v.stream[voice]:
                    self._streams[voice] = Stream(self.streamed[clip], self.sample_rate, bool(loop))
            elif kind == "stop":
                voice = command[1]
                if voice < len(v.clip) and v.active[voice] and not v.stopping[voice]:
                    v.stopping[voice] = True
                    self._stopping += 1
            elif kind == "pause":
                voice, paused = command[1:]
                if voice < len(v.clip) and v.active[voice]:
                    v.paused[voice] = paused
                    v.live[voice] = not paused
                    if not paused:
                        v.gain_from[voice] = 0.0  # back in with a fade, not a click
            elif kind == "buses":
                self._bus_gain = command[1]
            elif kind == "limiter":
                settings = command[1]
                if settings is None:
                    self.limiter = None
                elif self.limiter is None:
                    self.limiter = Limiter(self.sample_rate, *settings)
                else:
                    self.limiter.set(*settings)

    def _close_stream(self, voice: int) -> None:
        stream = self._streams.pop(voice, None)
        if stream is not None:
            stream.close()

    def _mix_stream(self, planes: np.ndarray, voice: int, target: np.ndarray) -> None:
        """A streamed voice's next block into `planes`, its gains ramped to `target` as the
        kernel's are."""
        v, frames = self._voices, planes.shape[1]
        block, ended = self._streams[voice].read(frames, self.wait_for_streams)
        if v.mono[voice]:
            block[:] = block.mean(axis=1, keepdims=True)
        ramp = np.arange(1, frames + 1, dtype=np.float32) / frames
        start = v.gain_from[voice]
        planes += block.T * (start[:, None] + (target - start)[:, None] * ramp)
        v.gain_from[voice] = target
        if ended:
            v.live[voice] = False

    def render(self, frames: int) -> np.ndarray:
        """The next `frames` of sound, (frames, 2) float32: the queued commands applied first."""
        began = time.perf_counter()
        with self._lock:
            commands, self._queue = self._queue, []
            bank = self.bank
        self._apply(commands, began)
        planes = np.zeros((2, frames), np.float32)  # the kernel's: each channel contiguous
        if self._used:
            self._mix(planes, bank, began)
        if self.limiter is not None:
            self.limiter.process(planes)
        self.frames_mixed += frames
        out = np.ascontiguousarray(planes.T)
        self.mix_seconds += time.perf_counter() - began
        return out

    def _mix(self, planes: np.ndarray, bank: ClipBank, began: float) -> None:
        """Every playing voice into `planes`; the voices that ended or faded out handed back.
        (Its few NumPy calls are a tenth of the mix at 1,000 voices: each is kept to what the
        block needs.)"""
        v, s = self._voices, slice(0, self._used)
        target = v.gain[s] * self._bus_gain[v.bus[s]][:, None]
        if self._stopping:
            target[v.stopping[s]] = 0.0
        rate = v.pitch[s] * bank.rate[v.clip[s]] / self.sample_rate
        fresh = [voice for voice in self.started_at if v.live[voice]] if self.started_at else []
        streaming = v.stream[s] if self._streams else None
        live = v.live[s] if streaming is None else v.live[s] & ~streaming  # the bank's voices: the kernel's
        playing = np.count_nonzero(live)
        mix_block(
            planes, bank.samples, bank.offset, bank.length, bank.channels, v.clip[s], v.position[s], rate,
            v.gain_from[s], target, v.loop[s], live, v.mono[s],
        )  # fmt: skip
        for voice in fresh:
            self.latencies.append(began - self.started_at.pop(voice))
        if streaming is not None:
            for row in np.flatnonzero(streaming & v.live[s]).tolist():
                self._mix_stream(planes, row, target[row])
            v.live[s] = np.where(streaming, v.live[s], live)
        elif np.count_nonzero(live) == playing and not self._stopping:
            return  # no clip ended, none faded out: nothing to hand back
        ended = np.flatnonzero(v.active[s] & ~v.live[s] & ~v.paused[s] & ~v.stopping[s])
        stopped = np.flatnonzero(v.stopping[s])
        for done in (ended, stopped):
            v.active[done] = v.live[done] = v.paused[done] = v.stopping[done] = False
            for row in done.tolist():
                self._close_stream(row)
        self._stopping = 0
        self._used = int(np.flatnonzero(v.active).max(initial=-1)) + 1
        if len(ended) or len(stopped):
            with self._lock:
                self._finished.extend(int(x) for x in ended)
                self._finished.extend(int(x) for x in stopped)
