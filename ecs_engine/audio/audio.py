"""The `Audio` resource: clips, buses, one-shot sounds, and the output the mixer plays into.

    audio = world.resources[Audio]
    boom = audio.load("boom.ogg")               # once; again gives the same clip
    audio.play(boom, at=(3.0, 0.0, -2.0))       # fire and forget, from any system
    audio.set_volume("music", 0.5); audio.mute("effects")

Buses: `master` (everything), `music` and `effects`, and any made with `add_bus(name)`; each
has a volume and a mute, and every bus but the master goes through the master. A sound's level
is its own volume times its bus's times the master's. Voices are the mixer's (mixer.py); this
side hands out their numbers and takes them back when the mixer says a voice is done."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import UsageError
from .clips import checked_samples, decode
from .limiter import CEILING_DB, RELEASE_S, check_settings
from .mixer import SAMPLE_RATE, Mixer
from .outputs import CaptureOutput, DeviceOutput
from .spatial import Listener, heard_points
from .streams import check_streamable

BUSES = ("master", "music", "effects")


class Audio:
    """World resource (see the module). `output`: "device" (the default sound device, the null
    output when there is none), "null" (no device at all), or a path: the WAV file the sound is
    captured into, frame by frame (`--audio-out`)."""

    def __init__(
        self,
        output: str | os.PathLike[str] = "device",
        sample_rate: int = SAMPLE_RATE,
        doppler_factor: float = 1.0,
        warn: Callable[[str], None] | None = None,
    ) -> None:
        if not isinstance(sample_rate, int) or not 8_000 <= sample_rate <= 192_000:
            raise UsageError(f"Audio: sample_rate must be an integer from 8,000 to 192,000 Hz, got {sample_rate!r}")
        if not np.isfinite(doppler_factor) or doppler_factor < 0:
            raise UsageError(f"Audio: doppler_factor must be 0 (off) or more, got {doppler_factor!r}")
        self.sample_rate = sample_rate
        self.doppler_factor = float(doppler_factor)
        # a sound that cannot play is said once, in one line, and the game goes on without it
        self.warn = warn or (lambda line: print(line, file=sys.stderr))
        self.said: list[str] = []
        self.notice: str | None = None  # a line for the user, printed by AudioSystem's next run (no device)
        self.mixer = Mixer(sample_rate)
        self._names: list[str] = list(BUSES)
        self._volume = np.ones(len(BUSES))
        self._muted = np.zeros(len(BUSES), bool)
        self._clips: dict[str, int] = {}
        self._clip_names: list[str] = []
        self._next_voice = 0
        self._free: list[int] = []
        self.owner: dict[int, int] = {}  # voice -> the entity whose AudioSource it plays (-1: a one-shot)
        # voice -> (at, volume, pitch, min and max distance) of a one-shot
        self.one_shots: dict[int, tuple[np.ndarray | None, float, float, float, float]] = {}
        self.listener = Listener.at_origin()
        self._last_perf = (0.0, 0)  # the mixer's seconds and frames at the last perf_line
        if output in ("device", "null"):
            self.output: DeviceOutput | CaptureOutput = DeviceOutput(self.mixer, null=output == "null")
        else:
            self.output = CaptureOutput(self.mixer, output)
            self.mixer.wait_for_streams = True
        self._send_buses()
        self.limiting: tuple[float, float] | None = (CEILING_DB, RELEASE_S)  # limit()'s ceiling dB and release s

    # ------------------------------------------------------------------ clips
    def load(self, path: str | os.PathLike[str], stream: bool = False, strict: bool = False) -> int:
        """The clip of a sound file (WAV, FLAC, MP3, Ogg Vorbis): its handle. Decoded once into
        memory, or with `stream` (music) decoded a little at a time by each voice that plays it
        (streams.py; such a voice plays at the clip's own pitch: pitch and Doppler pass it by).
        A file that is missing or cannot be decoded is said in one line and gives a silent clip,
        so the game goes on without that sound; with `strict`, UsageError instead."""
        name = os.fspath(path)
        key = f"{'stream' if stream else 'memory'}:{os.path.realpath(name)}"
        if key not in self._clips:
            try:
                if stream:
                    check_streamable(name)
                    self._clip_names.append(name)
                    self._clips[key] = self.mixer.add_stream(os.path.realpath(name))
                else:
                    self._clips[key] = self._add(decode(path, self.sample_rate), self.sample_rate, name)
            except UsageError as error:
                if strict:
                    raise
                self.say(f"{error}: it plays as silence")
                self._clips[key] = self._add(np.zeros((1, 1), np.float32), self.sample_rate, f"{name} (silent)")
        return self._clips[key]

    def say(self, line: str) -> None:
        """Tell the user, once per line, of a sound that cannot play."""
        if line not in self.said:
            self.said.append(line)
            self.warn(line)

    def clip(self, samples: np.ndarray, rate: int | None = None, name: str = "clip") -> int:
        """A clip from samples ((frames,) or (frames, 1 or 2), -1..1) at `rate` Hz (the mixer's by
        default): a synthesised sound. Its handle."""
        rate = self.sample_rate if rate is None else rate
        if not isinstance(rate, int) or rate <= 0:
            raise UsageError(f"clip {name}: rate must be a positive integer, got {rate!r}")
        return self._add(checked_samples(samples, name), rate, name)

    def _add(self, samples: np.ndarray, rate: int, name: str) -> int:
        self._clip_names.append(name)
        return self.mixer.add_clip(samples, rate)

    def clip_name(self, clip: int) -> str:
        return self._clip_names[clip] if 0 <= clip < len(self._clip_names) else f"#{clip}"

    @property
    def clip_count(self) -> int:
        return len(self._clip_names)

    def check_clip(self, clip: int, who: str) -> None:
        if not 0 <= clip < len(self._clip_names):
            raise UsageError(f"{who}: clip {clip} is not a clip of the Audio resource (it has {len(self._clip_names)})")

    # ------------------------------------------------------------------ buses
    def add_bus(self, name: str, volume: float = 1.0) -> int:
        """A bus of its own (through the master): its number, for AudioSource.bus and play()."""
        if name in self._names:
            raise UsageError(f"Audio.add_bus: there is a bus {name!r} already")
        self._names.append(name)
        self._volume = np.append(self._volume, 1.0)
        self._muted = np.append(self._muted, False)
        bus = len(self._names) - 1
        self.set_volume(bus, volume)
        return bus

    def bus(self, bus: int | str) -> int:
        """A bus's number, by name or number."""
        if isinstance(bus, str):
            if bus not in self._names:
                raise UsageError(f"no bus {bus!r}: the buses are {', '.join(self._names)}")
            return self._names.index(bus)
        if not 0 <= int(bus) < len(self._names):
            raise UsageError(f"no bus {bus}: there are {len(self._names)} ({', '.join(self._names)})")
        return int(bus)

    @property
    def buses(self) -> list[str]:
        return list(self._names)

    def volume(self, bus: int | str) -> float:
        return float(self._volume[self.bus(bus)])

    def muted(self, bus: int | str) -> bool:
        return bool(self._muted[self.bus(bus)])

    def set_volume(self, bus: int | str, volume: float) -> None:
        number = self.bus(bus)
        if not np.isfinite(volume) or volume < 0:
            raise UsageError(f"bus {self._names[number]}: volume must be 0 or more, got {volume!r}")
        self._volume[number] = volume
        self._send_buses()

    def mute(self, bus: int | str, muted: bool = True) -> None:
        self._muted[self.bus(bus)] = muted
        self._send_buses()

    def bus_gains(self) -> np.ndarray:
        """Each bus's gain as the mixer applies it: its volume, times the master's unless it is it."""
        own = np.where(self._muted, 0.0, self._volume)
        gains = own * own[0]
        gains[0] = own[0]
        return gains

    def limit(self, ceiling_db: float | None = CEILING_DB, release: float = RELEASE_S) -> None:
        """The master bus's peak limiter (limiter.py; on by default at 0 dB, 0.1 s): no sound
        leaves above `ceiling_db` (dB of full scale, -60 to 0), and the gain it takes away comes
        back over about `release` seconds; `ceiling_db` None turns it off (a mix over full scale
        is then clipped by the device)."""
        if ceiling_db is None:
            self.limiting = None
        else:
            wrong = check_settings(ceiling_db, release)
            if wrong is not None:
                raise UsageError(f"Audio.limit: {wrong}")
            self.limiting = (float(ceiling_db), float(release))
        self.mixer.set_limiter(self.limiting)

    def _send_buses(self) -> None:
        self.mixer.set_buses(self.bus_gains())

    # ------------------------------------------------------------------ voices
    def voice(self, owner: int) -> int:
        """A free voice number, now owned by `owner` (an entity, or -1 for a one-shot)."""
        voice = self._free.pop() if self._free else self._next_voice
        if voice == self._next_voice:
            self._next_voice += 1
        self.owner[voice] = owner
        return voice

    def collect(self) -> list[int]:
        """The voices the mixer finished since the last call, given back (their owners first)."""
        done = self.mixer.finished()
        for voice in done:
            self.owner.pop(voice, None)
            self.one_shots.pop(voice, None)
            self._free.append(voice)
        return done

    def play(
        self,
        clip: int,
        at: Sequence[float] | np.ndarray | None = None,
        volume: float = 1.0,
        pitch: float = 1.0,
        bus: int | str = "effects",
        loop: bool = False,
        min_distance: float = 1.0,
        max_distance: float = 1000.0,
    ) -> int:
        """Play `clip` once (fire and forget): heard from the world point `at` (spatial: inverse
        distance between `min_distance` and `max_distance`, panned, its level followed as the
        listener moves) or, without one, as it is. Its voice number (for `stop`)."""
        self.check_clip(clip, "Audio.play")
        if not np.isfinite(volume) or volume < 0:
            raise UsageError(f"Audio.play: volume must be 0 or more, got {volume!r}")
        if not np.isfinite(pitch) or pitch <= 0:
            raise UsageError(f"Audio.play: pitch must be more than 0, got {pitch!r}")
        point = None
        if at is not None:
            point = np.asarray(at, np.float64).reshape(-1)
            if point.shape != (3,) or not np.isfinite(point).all():
                raise UsageError(f"Audio.play: at must be a finite (x, y, z), got {at!r}")
        if not (np.isfinite(min_distance) and np.isfinite(max_distance) and 0 < min_distance <= max_distance):
            raise UsageError(
                f"Audio.play: min_distance and max_distance must be finite, more than 0 and in order, "
                f"got {min_distance!r} and {max_distance!r}"
            )
        number = self.bus(bus)
        voice = self.voice(-1)
        self.one_shots[voice] = (point, float(volume), float(pitch), float(min_distance), float(max_distance))
        left, right, factor = self.one_shot_gains(point, volume, min_distance, max_distance)
        self.mixer.start(voice, clip, (left, right), pitch * factor, loop, point is not None, number)
        return voice

    def one_shot_gains(
        self, point: np.ndarray | None, volume: float, near: float = 1.0, far: float = 1000.0
    ) -> tuple[float, float, float]:
        """(left, right, Doppler factor) of a one-shot heard from `point` by the listener."""
        if point is None:
            return volume, volume, 1.0
        left, right, factor = heard_points(self.listener, point[None, :], volume, near, far, self.doppler_factor)
        return float(left[0]), float(right[0]), float(factor[0])

    def stop(self, voice: int) -> None:
        """Stop a one-shot (with a short fade)."""
        if voice in self.owner:
            self.mixer.stop(voice)

    # ------------------------------------------------------------------ the frame
    def advance(self, seconds: float) -> None:
        """After the frame's parameters: a captured output mixes the frame's `seconds` of sound."""
        self.output.advance(seconds)

    @property
    def underruns(self) -> int:
        return self.output.underruns

    def perf_line(self) -> str:
        """The Perf window's and the perf lines' word on the sound: the mixer's share of a core
        since the last line, the voices, the underruns, and how deep the limiter cut since then."""
        mixer = self.mixer
        seconds, frames = mixer.mix_seconds, mixer.frames_mixed
        last, self._last_perf = self._last_perf, (seconds, frames)
        sound_s = (frames - last[1]) / self.sample_rate
        share = 100.0 * (seconds - last[0]) / sound_s if sound_s > 0 else 0.0
        voices = f"{len(self.owner)} voice{'' if len(self.owner) == 1 else 's'}"
        limiter = mixer.limiter
        lowest = limiter.take_deepest() if limiter is not None else 1.0
        limiting = f", limiting {20.0 * np.log10(lowest):.1f} dB" if lowest < 1.0 else ""
        return f"sound mix {share:.1f}% of a core, {voices}, underruns {self.underruns}{limiting}"

    def latency_ms(self) -> list[float]:
        """For the last voices started: ms from each start call to the block that mixed it first."""
        return [1e3 * seconds for seconds in self.mixer.latencies]

    def close(self) -> None:
        self.output.close()

    def __repr__(self) -> str:
        return f"Audio({self.output.backend}, {self.sample_rate} Hz, {len(self.owner)} voices, {self.clip_count} clips)"
