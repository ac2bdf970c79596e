"""A game with sound, captured: MinimalPlugins and AudioPlugin writing a WAV file, and the laws
the captures are checked against, written from OpenAL 1.1's specification (section 3.4) and the
equal-power panning law, apart from the engine's own code (ecs_engine/audio/spatial.py)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine import App, MinimalPlugins
from ecs_engine.audio import Audio, AudioPlugin
from ecs_engine.audio.outputs import read_wav

RATE = 48_000
FPS = 60


def tone(freq: float, seconds: float = 1.0, rate: int = RATE) -> np.ndarray:
    t = np.arange(round(seconds * rate)) / rate
    return np.sin(2 * np.pi * freq * t).astype(np.float32)


def capture(
    tmp: Path, setup: Callable[[Any, Audio], Any], frames: int, name: str = "out.wav", every: Any = None, **plugin: Any
) -> tuple[np.ndarray, App]:
    """Run `setup(world, audio)` as the startup system, then `frames` frames at 60 FPS (with
    `every(world, frame)` as an update system), capturing the sound: ((samples, 2), the App)."""
    path = tmp / name
    app = App(title="sound test").add_plugins(MinimalPlugins, AudioPlugin(output=str(path), **plugin))
    app.add_startup_systems(lambda world, dt: setup(world, world.resources[Audio]))
    if every is not None:
        count = [0]

        def each(world: Any, dt: float) -> None:
            count[0] += 1
            every(world, count[0])

        app.add_systems("update", each)
    app.run(frames=frames)
    samples, rate = read_wav(path)
    assert rate == RATE
    return samples, app


def rms(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(np.asarray(x, np.float64) ** 2, axis=0))


# ---------------------------------------------------------------- the references (OpenAL 1.1, 3.4)
def inverse_clamped(d: float, ref: float, far: float, rolloff: float) -> float:
    d = min(max(d, ref), far)
    return ref / (ref + rolloff * (d - ref))


def linear_clamped(d: float, ref: float, far: float, rolloff: float) -> float:
    d = min(max(d, ref), far)
    return max(0.0, 1.0 - rolloff * (d - ref) / (far - ref))


def exponential_clamped(d: float, ref: float, far: float, rolloff: float) -> float:
    d = min(max(d, ref), far)
    return (d / ref) ** (-rolloff)


def equal_power(azimuth: float) -> tuple[float, float]:
    """Left and right gains of a source at `azimuth` radians to the listener's right (0: ahead)."""
    pan = math.sin(azimuth)
    angle = (pan + 1) * math.pi / 4
    return math.cos(angle), math.sin(angle)


def doppler_frequency(freq: float, source_speed_toward: float, listener_speed_toward: float = 0.0) -> float:
    c = 343.3
    return freq * (c + listener_speed_toward) / (c - source_speed_toward)


def peak_frequency(x: np.ndarray, rate: int = RATE) -> float:
    """The strongest frequency of `x`, refined between FFT bins (a Hann window, the peak's
    log-magnitude parabola)."""
    x = np.asarray(x, np.float64)
    spectrum = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    k = int(np.argmax(spectrum[1:-1])) + 1
    a, b, c = np.log(spectrum[k - 1 : k + 2] + 1e-30)
    shift = 0.5 * (a - c) / (a - 2 * b + c)
    return (k + shift) * rate / len(x)
