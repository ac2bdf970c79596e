"""Sound, captured with --audio-out's path (AudioPlugin writing a WAV), against the laws written
apart from the engine in audio_scene.py: panning, the three roll-off models, Doppler, the cone,
buses, loops without a seam, sources that start, end, stop and go away, and determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest
from audio_scene import (
    FPS,
    RATE,
    capture,
    doppler_frequency,
    equal_power,
    exponential_clamped,
    inverse_clamped,
    linear_clamped,
    peak_frequency,
    rms,
    tone,
)

from ecs_engine.audio import Audio
from ecs_engine.components import Transform, Velocity
from ecs_engine.components.audio import EXPONENTIAL, INVERSE, LINEAR, MUSIC, AudioListener, AudioSource
from ecs_engine.maths.camera import look_rotation

SETTLE = 2 * RATE // FPS  # the first frames: the sources start in the first, ramps settle by the second


def _sources(world, audio, places, **fields):
    clip = audio.clip(tone(500.0), name="tone")
    for place in places:
        world.spawn(Transform(position=place), AudioSource(clip=clip, loop=True, **fields))


def test_panning_is_equal_power_around_the_listener(tmp_path):
    """One source at a time at azimuths around a listener looking down -z: each channel's level
    is the equal-power law's (a listener turned by a quarter turn hears the same source ahead)."""
    for azimuth in (-math.pi / 2, -math.pi / 4, 0.0, math.pi / 6, math.pi / 2, 3 * math.pi / 4):
        place = (2 * math.sin(azimuth), 0.0, -2 * math.cos(azimuth))

        def setup(world, audio, place=place):
            world.spawn(Transform(), AudioListener())
            _sources(world, audio, [place], min_distance=2.0)

        samples, _ = capture(tmp_path, setup, 12)
        left, right = rms(samples[SETTLE:]) / (1 / math.sqrt(2))  # a sine's RMS is 1/sqrt(2) of its peak
        want = equal_power(azimuth)
        assert left == pytest.approx(want[0], abs=2e-3) and right == pytest.approx(want[1], abs=2e-3), azimuth

    def turned(world, audio):  # the listener turned to face +x: a source at +x is ahead, centred
        world.spawn(Transform(rotation=look_rotation((1.0, 0.0, 0.0))), AudioListener())
        _sources(world, audio, [(2.0, 0.0, 0.0)], min_distance=2.0)

    samples, _ = capture(tmp_path, turned, 12)
    assert rms(samples[SETTLE:]) * math.sqrt(2) == pytest.approx(equal_power(0.0), abs=2e-3)


@pytest.mark.parametrize(
    ("model", "law"), [(INVERSE, inverse_clamped), (LINEAR, linear_clamped), (EXPONENTIAL, exponential_clamped)]
)
def test_each_rolloff_model_at_several_distances(tmp_path, model, law):
    """Sources straight ahead at distances inside, across and past the clamp range, one per
    channel pair: each level is the model's (OpenAL's clamped formula) with its rolloff."""
    ref, far, rolloff = 2.0, 40.0, 1.5
    for distance in (0.5, 2.0, 3.0, 7.5, 20.0, 39.0, 80.0):

        def setup(world, audio, distance=distance):
            world.spawn(Transform(), AudioListener())
            _sources(
                world, audio, [(0.0, 0.0, -distance)], model=model, min_distance=ref, max_distance=far, rolloff=rolloff
            )

        samples, _ = capture(tmp_path, setup, 8)
        level = rms(samples[SETTLE:])[0] * math.sqrt(2) / math.cos(math.pi / 4)
        assert level == pytest.approx(law(distance, ref, far, rolloff), rel=2e-3, abs=1e-6), distance


def test_doppler_shift_of_a_moving_source_within_one_percent(tmp_path):
    """A 1 kHz source flying at 40 m/s toward the listener, then one flying away, and a listener
    running at 25 m/s toward a still one: the captured frequency is OpenAL's f (c + vl) / (c - vs)
    within 1% (the test's tolerance; the error is far smaller)."""
    cases = [((0.0, 0.0, -300.0), (0.0, 0.0, 40.0), None), ((0.0, 0.0, -5.0), (0.0, 0.0, -40.0), None)]
    cases.append(((0.0, 0.0, -300.0), None, (0.0, 0.0, -25.0)))
    for start, source_v, listener_v in cases:

        def setup(world, audio, start=start, source_v=source_v, listener_v=listener_v):
            ear = [Transform(), AudioListener()] + ([Velocity(linear=listener_v)] if listener_v else [])
            world.spawn(*ear)
            parts = [Transform(position=start), AudioSource(clip=audio.clip(tone(1000.0)), loop=True)]
            world.spawn(*parts, *([Velocity(linear=source_v)] if source_v else []))

        samples, _ = capture(tmp_path, setup, 40)
        measured = peak_frequency(samples[SETTLE:, 0])
        toward = 0.0 if source_v is None else source_v[2]  # the source is along -z: +z is toward the listener
        listener_toward = 0.0 if listener_v is None else -listener_v[2]
        want = doppler_frequency(1000.0, toward, listener_toward)
        assert abs(measured - want) / want < 0.01, (measured, want)
        assert abs(measured - want) / want < 0.002  # what the mixer actually achieves


def test_cone_gains_inside_between_and_outside(tmp_path):
    """A source facing the listener, turned half way through its cone's edge, and facing away:
    1, the interpolated gain, and the outer gain."""
    for turn, want in ((0.0, 1.0), (50.0, 1.0 + (50.0 - 30.0) / (60.0 - 30.0) * (0.25 - 1.0)), (120.0, 0.25)):

        def setup(world, audio, turn=turn):
            world.spawn(Transform(position=(0.0, 0.0, 3.0)), AudioListener())
            a = math.radians(turn)
            facing = look_rotation((math.sin(a), 0.0, math.cos(a)))  # forward -z turned toward +z by `turn`
            clip = audio.clip(tone(500.0))
            source = AudioSource(clip=clip, loop=True, cone_inner=60.0, cone_outer=120.0, cone_outer_gain=0.25)
            world.spawn(Transform(rotation=facing), source)

        samples, _ = capture(tmp_path, setup, 8)
        level = rms(samples[SETTLE:])[0] * math.sqrt(2) / math.cos(math.pi / 4) / inverse_clamped(3.0, 1.0, 1e3, 1.0)
        assert level == pytest.approx(want, rel=3e-3), turn


def test_bus_volumes_mutes_and_the_master(tmp_path):
    """Music (not spatial) on the music bus at 0.5 under a master at 0.5; then the music bus
    muted; an effect on a bus of its own at 0.2: each level is its volume times its bus's times
    the master's."""

    def setup(world, audio):
        audio.set_volume("master", 0.5)
        audio.set_volume("music", 0.5)
        engine = audio.add_bus("engine", 0.2)
        clip = audio.clip(tone(500.0))
        world.spawn(Transform(), AudioSource(clip=clip, loop=True, spatial=False, bus=MUSIC, volume=0.8))
        world.spawn(Transform(), AudioSource(clip=audio.clip(tone(700.0)), loop=True, spatial=False, bus=engine))

    def every(world, frame):
        if frame == 20:
            world.resources[Audio].mute("music")

    samples, _ = capture(tmp_path, setup, 40, every=every)
    first, after = samples[SETTLE : 19 * RATE // FPS, 0], samples[22 * RATE // FPS :, 0]
    spectrum = lambda x, f: 2 * np.abs(np.fft.rfft(x))[round(f * len(x) / RATE)] / len(x)  # a bin's amplitude
    assert spectrum(first[:4800], 500.0) == pytest.approx(0.8 * 0.5 * 0.5, rel=1e-3)
    assert spectrum(first[:4800], 700.0) == pytest.approx(0.2 * 0.5, rel=1e-3)
    assert spectrum(after[:4800], 500.0) < 1e-6
    assert spectrum(after[:4800], 700.0) == pytest.approx(0.2 * 0.5, rel=1e-3)


def test_a_loop_plays_without_a_seam(tmp_path):
    """A clip of whole periods (480 Hz, 0.1 s) looped for 0.75 s is the same as an endless sine:
    no step at the seams; and at a pitch that does not divide the clip, the seam is still smooth."""

    def setup(world, audio):
        world.spawn(Transform(), AudioSource(clip=audio.clip(tone(480.0, 0.1)), loop=True, spatial=False))

    samples, _ = capture(tmp_path, setup, 45)
    n = np.arange(len(samples))
    assert np.abs(samples[:, 0] - np.sin(2 * np.pi * 480.0 * n / RATE)).max() < 1e-5

    def pitched(world, audio):
        clip = audio.clip(tone(480.0, 0.1))
        world.spawn(Transform(), AudioSource(clip=clip, loop=True, spatial=False, pitch=1.37))

    samples, _ = capture(tmp_path, pitched, 45)
    steps = np.abs(np.diff(samples[:, 0]))
    largest = 2 * np.sin(np.pi * 480.0 * 1.37 / RATE)  # a sine's largest step between samples
    assert steps.max() < largest * 1.01


def test_same_run_writes_the_same_file_twice(tmp_path):
    """Sources that move, start, stop and play one-shots, run twice: byte for byte the same WAV."""

    def setup(world, audio):
        world.spawn(Transform(), AudioListener())
        clip = audio.clip(tone(300.0, 0.3))
        world.spawn(Transform(position=(-3.0, 0.0, -4.0)), Velocity(linear=(2.0, 0.0, 1.0)), AudioSource(clip=clip))
        world.resources["shot"] = audio.clip(tone(900.0, 0.05))

    def every(world, frame):
        if frame % 7 == 0:
            world.resources[Audio].play(world.resources["shot"], at=(frame * 0.1, 0.0, -2.0))

    first, _ = capture(tmp_path, setup, 50, name="a.wav", every=every)
    capture(tmp_path, setup, 50, name="b.wav", every=every)
    assert (tmp_path / "a.wav").read_bytes() == (tmp_path / "b.wav").read_bytes()
    assert rms(first).min() > 0.01 and len(first) == 50 * RATE // FPS


def test_a_stereo_clip_keeps_its_channels_unless_heard_from_a_point(tmp_path):
    """A stereo clip (440 Hz left, 660 Hz right) not spatial: each channel its own tone; spatial
    and ahead of the listener: both channels the two tones averaged, equal-power centred."""
    both = np.c_[tone(440.0), tone(660.0)]

    def flat(world, audio):
        world.spawn(Transform(), AudioSource(clip=audio.clip(both), loop=True, spatial=False))

    samples, _ = capture(tmp_path, flat, 12)
    n = np.arange(len(samples))
    np.testing.assert_allclose(samples[:, 0], np.sin(2 * np.pi * 440.0 * n / RATE), atol=1e-5)
    np.testing.assert_allclose(samples[:, 1], np.sin(2 * np.pi * 660.0 * n / RATE), atol=1e-5)

    def ahead(world, audio):
        world.spawn(Transform(), AudioListener())
        world.spawn(Transform(position=(0.0, 0.0, -1.0)), AudioSource(clip=audio.clip(both), loop=True))

    samples, _ = capture(tmp_path, ahead, 12)
    mean = 0.5 * (np.sin(2 * np.pi * 440.0 * n / RATE) + np.sin(2 * np.pi * 660.0 * n / RATE))
    for channel in (0, 1):
        np.testing.assert_allclose(samples[SETTLE:, channel], math.cos(math.pi / 4) * mean[SETTLE:], atol=1e-5)
