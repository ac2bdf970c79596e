"""The master bus's limiter (ecs_engine/audio/limiter.py), captured as a game plays it: a mix over
the ceiling leaves at the ceiling, with the gain a reference limiter written here, one frame at a
time, gives; a mix under it passes bit for bit; the gain comes back over the release; off, the
loud mix passes as it is; the Perf line says how deep it cut; bad settings are refused."""

from __future__ import annotations

import math

import numpy as np
import pytest
from audio_scene import RATE, capture, tone

from ecs_engine.audio import Audio
from ecs_engine.components import Transform
from ecs_engine.components.audio import AudioSource
from ecs_engine.errors import UsageError


def _two_tones(level: float, seconds: float = 1.0):
    """Two tones, not spatial, each at `level`: together they peak near 2 * level."""

    def setup(world, audio):
        for freq in (300.0, 470.0):
            clip = audio.clip(tone(freq, seconds))
            world.spawn(Transform(), AudioSource(clip=clip, spatial=False, volume=level))

    return setup


def _reference(mix: np.ndarray, ceiling: float, release: float) -> tuple[np.ndarray, np.ndarray]:
    """The limiter's law, one frame at a time: the gain recovers towards 1 (1 - 1/e of the way per
    `release`), and falls to ceiling / peak where the louder channel would pass the ceiling."""
    recover = 1.0 - math.exp(-1.0 / (release * RATE))
    out, gains, g = mix.astype(np.float64).copy(), np.ones(len(mix)), 1.0
    for i, peak in enumerate(np.abs(mix).max(axis=1).astype(np.float64)):
        g += (1.0 - g) * recover
        if peak * g > ceiling:
            g = ceiling / peak
        gains[i] = g
        out[i] *= g
    return out, gains


def test_a_loud_mix_leaves_at_the_ceiling_with_the_reference_gain(tmp_path):
    """Two tones at 0.9 each (peaks near 1.8): off, the capture passes full scale; on, no sample
    passes the ceiling (0 dB, then -6 dB), and each sample is the unlimited mix times the
    reference's gain."""

    def off(world, audio):
        audio.limit(None)
        _two_tones(0.9)(world, audio)

    loud, _ = capture(tmp_path, off, 20, name="off.wav")
    assert np.abs(loud).max() > 1.7
    for ceiling_db in (0.0, -6.0):

        def setup(world, audio, ceiling_db=ceiling_db):
            audio.limit(ceiling_db, release=0.05)
            _two_tones(0.9)(world, audio)

        limited, _ = capture(tmp_path, setup, 20, name=f"on{ceiling_db}.wav")
        ceiling = 10.0 ** (ceiling_db / 20.0)
        assert np.abs(limited).max() <= ceiling * (1 + 1e-6)
        want, gains = _reference(loud, ceiling, 0.05)
        assert gains.min() < 0.6 * ceiling  # it did cut
        np.testing.assert_allclose(limited, want, atol=2e-6)


def test_a_mix_under_the_ceiling_passes_bit_for_bit(tmp_path):
    quiet_on, _ = capture(tmp_path, _two_tones(0.4), 12, name="on.wav")

    def off(world, audio):
        audio.limit(None)
        _two_tones(0.4)(world, audio)

    quiet_off, _ = capture(tmp_path, off, 12, name="off.wav")
    assert np.abs(quiet_off).max() < 0.85
    assert np.array_equal(quiet_on, quiet_off)


def test_the_gain_comes_back_over_the_release(tmp_path):
    """A loud burst (0.2 s) over a quiet tone that goes on: after the burst the quiet tone comes
    back as the reference's release brings it, within a release of the burst's end to 1 - 1/e of
    the cut, and whole after five."""
    release = 0.1

    def sources(world, audio):
        world.spawn(Transform(), AudioSource(clip=audio.clip(tone(440.0, 2.0)), spatial=False, volume=0.3))
        world.spawn(Transform(), AudioSource(clip=audio.clip(tone(97.0, 0.2)), spatial=False, volume=1.0))

    def on(world, audio):
        audio.limit(0.0, release=release)
        sources(world, audio)

    def off(world, audio):
        audio.limit(None)
        sources(world, audio)

    limited, _ = capture(tmp_path, on, 60, name="on.wav")
    raw, _ = capture(tmp_path, off, 60, name="off.wav")
    want, gains = _reference(raw, 1.0, release)
    np.testing.assert_allclose(limited, want, atol=2e-6)
    end = int(np.flatnonzero(gains < 1.0 - 1e-9).max())  # where the reference's gain is back at 1
    cut = 1.0 - gains[: int(0.2 * RATE)].min()
    later = int(0.2 * RATE) + int(release * RATE)
    assert 1.0 - gains[later] < cut / math.e + 1e-3
    assert end < int(0.2 * RATE) + int(20 * release * RATE)
    assert 1.0 - gains[int(0.2 * RATE) + int(5 * release * RATE)] < 0.01 * cut + 1e-3


def test_the_perf_line_says_how_deep_it_cut(tmp_path):
    _, app = capture(tmp_path, _two_tones(0.9), 10)
    line = app.world.resources[Audio].perf_line()
    assert "limiting -" in line
    depth = float(line.split("limiting ")[1].split(" dB")[0])
    assert -7.0 < depth < -3.0  # 1.8 down to 1.0 is about -5.1 dB
    assert "limiting" not in app.world.resources[Audio].perf_line()  # nothing cut since the last line


def test_bad_limiter_settings_are_refused():
    audio = Audio(output="null")
    try:
        for ceiling, release in ((3.0, 0.1), (float("nan"), 0.1), (-1.0, 0.0), (-1.0, float("inf")), ("0", 0.1)):
            with pytest.raises(UsageError, match=r"Audio\.limit: the limiter's"):
                audio.limit(ceiling, release)  # type: ignore[arg-type]
        assert audio.limiting == (0.0, 0.1)  # the default stands
    finally:
        audio.close()
