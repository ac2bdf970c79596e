"""A source's life (autoplay, the end of a clip, stop, pause, another clip, destroyed), one-shots,
sound files, and bad input: one clear error, and the game's sound goes on."""

from __future__ import annotations

import re
import wave

import numpy as np
import pytest
from audio_scene import FPS, RATE, capture, peak_frequency, rms, tone

from ecs_engine.app.output_files import check_outputs
from ecs_engine.audio import Audio
from ecs_engine.components import Transform
from ecs_engine.components.audio import AudioSource
from ecs_engine.errors import UsageError

BLOCK = RATE // FPS  # a frame's samples in a capture


def _flat(clip: int, **fields) -> AudioSource:
    return AudioSource(clip=clip, spatial=False, **fields)


def test_a_clip_that_ends_clears_playing_and_frees_its_voice(tmp_path):
    """A 0.1 s clip without loop: sound for 0.1 s, silence after, `playing` cleared, no voice left."""

    def setup(world, audio):
        world.resources["e"] = world.spawn(Transform(), _flat(audio.clip(tone(440.0, 0.1))))

    samples, app = capture(tmp_path, setup, 20)
    world = app.world
    assert rms(samples[: RATE // 10 - 10])[0] > 0.5 and np.abs(samples[RATE // 10 + 1 :]).max() == 0.0
    assert not world.get(world.resources["e"], AudioSource).playing
    assert world.resources[Audio].owner == {}


def test_autoplay_off_waits_for_playing_and_stop_fades_out(tmp_path):
    """autoplay=False is silent until a system sets `playing`; clearing it stops the sound with a
    fade of one block, not a step."""

    def setup(world, audio):
        world.resources["e"] = world.spawn(Transform(), _flat(audio.clip(tone(440.0)), autoplay=False, loop=True))

    def every(world, frame):
        e = world.resources["e"]
        if frame in (10, 20):
            world.set(e, AudioSource, playing=frame == 10)

    samples, _ = capture(tmp_path, setup, 30, every=every)
    assert np.abs(samples[: 9 * BLOCK]).max() == 0.0
    assert rms(samples[10 * BLOCK : 19 * BLOCK])[0] > 0.6
    fade = np.abs(samples[19 * BLOCK : 21 * BLOCK, 0])
    assert fade.max() > 0.1 and np.abs(samples[21 * BLOCK :]).max() == 0.0
    assert np.abs(np.diff(samples[:, 0])).max() < 2 * np.sin(np.pi * 440.0 / RATE) * 1.01  # no click anywhere


def test_pause_holds_the_clip_where_it_is(tmp_path):
    """A ramp clip paused for 10 frames goes on from where it stopped, not from where it would be."""
    ramp = np.linspace(0.0, 1.0, RATE, dtype=np.float32)

    def setup(world, audio):
        world.resources["e"] = world.spawn(Transform(), _flat(audio.clip(ramp)))

    def every(world, frame):
        if frame in (10, 20):
            e = world.resources["e"]
            world.set(e, AudioSource, paused=frame == 10)

    samples, _ = capture(tmp_path, setup, 40, every=every)
    before = samples[9 * BLOCK - 1, 0]  # the last sample at full level before the pause's fade block
    after = samples[21 * BLOCK + BLOCK // 2, 0]  # in the block after the resume's fade-in
    assert 0 < after - before < 3 * BLOCK / RATE  # it went on from about where it was: not 10 frames later


def test_destroying_a_source_or_changing_its_clip(tmp_path):
    """A looping source destroyed: its voice fades and is given back. Another's clip changed:
    the new clip plays from its start."""

    def setup(world, audio):
        world.resources["a"] = world.spawn(Transform(), _flat(audio.clip(tone(300.0)), loop=True))
        world.resources["b"] = world.spawn(Transform(), _flat(audio.clip(tone(500.0)), loop=True))
        world.resources["c"] = audio.clip(tone(800.0))

    def every(world, frame):
        if frame == 10:
            world.destroy(world.resources["a"])
            b = world.resources["b"]
            world.set(b, AudioSource, clip=world.resources["c"])

    samples, app = capture(tmp_path, setup, 30, every=every)
    late = samples[13 * BLOCK :, 0]
    spectrum = np.abs(np.fft.rfft(late * np.hanning(len(late))))
    freqs = np.fft.rfftfreq(len(late), 1 / RATE)
    assert freqs[np.argmax(spectrum)] == pytest.approx(800.0, abs=5.0)
    for gone in (300.0, 500.0):
        assert spectrum[np.argmin(np.abs(freqs - gone))] < 1e-3 * spectrum.max()
    assert len(app.world.resources[Audio].owner) == 1


def test_one_shots_play_and_give_their_voices_back(tmp_path):
    """Ten overlapping one-shots from a system: all heard, all voices free once they end."""

    def setup(world, audio):
        world.resources["shot"] = audio.clip(tone(600.0, 0.05))

    def every(world, frame):
        if frame <= 10:
            world.resources[Audio].play(world.resources["shot"], at=(1.0, 0.0, -1.0), volume=0.5)

    samples, app = capture(tmp_path, setup, 30, every=every)
    assert rms(samples[BLOCK : 10 * BLOCK]).min() > 0.05
    assert app.world.resources[Audio].owner == {} and np.abs(samples[-BLOCK:]).max() == 0.0


def test_sound_files_decode_and_bad_ones_say_why(tmp_path):
    """A 16-bit mono WAV at 24 kHz loads as the mixer's rate, mono, the same sound; loading it
    again gives the same clip. A missing file, a file that is not sound, and samples with NaN are
    one line each, and the clips already loaded stay."""
    path = tmp_path / "beep.wav"
    data = (tone(1000.0, 0.2, 24_000) * 16000).astype("<i2")
    with wave.open(str(path), "wb") as f:
        f.setnchannels(1), f.setsampwidth(2), f.setframerate(24_000), f.writeframes(data.tobytes())
    audio = Audio("null")
    try:
        clip = audio.load(path)
        assert audio.load(tmp_path / "." / "beep.wav") == clip
        bank = audio.mixer.bank
        samples = bank.samples[bank.offset[clip] : bank.offset[clip] + bank.length[clip]]
        assert bank.channels[clip] == 1 and bank.length[clip] == RATE // 5
        middle = samples[500:-500]  # away from the resampler's edges
        assert rms(middle) * np.sqrt(2) == pytest.approx(16000 / 32768, rel=0.01)
        assert peak_frequency(middle) == pytest.approx(1000.0, rel=1e-3)
        (tmp_path / "notes.txt").write_text("not a sound\n" * 50)
        for bad, says in (("missing.ogg", "no such file"), ("notes.txt", "not a WAV, FLAC, MP3 or Ogg Vorbis")):
            with pytest.raises(UsageError, match=says) as error:
                audio.load(tmp_path / bad, strict=True)
            assert "\n" not in str(error.value) and bad in str(error.value)
            said = []
            audio.warn = said.append
            silent = audio.load(tmp_path / bad)  # a game's load: one line, a silent clip, the game goes on
            assert audio.load(tmp_path / bad) == silent and len(said) == 1 and says in said[0]
            assert said[0].endswith("it plays as silence") and audio.mixer.bank.length[silent] == 1
        with pytest.raises(UsageError, match="NaN"):
            audio.clip(np.array([0.0, np.nan]))
        with pytest.raises(UsageError, match="volume must be 0 or more"):
            audio.set_volume("music", -1.0)
        with pytest.raises(UsageError, match="no bus 'voices'"):
            audio.play(clip, bus="voices")
        with pytest.raises(UsageError, match="sample_rate"):
            Audio("null", sample_rate=1000)
        assert audio.clip_count == 3  # the file, and the two silent stand-ins
    finally:
        audio.close()


def test_a_source_with_an_unknown_clip_or_bus_is_said_once_and_the_game_goes_on(tmp_path, capsys):
    """One line each, naming the entity and the field, said once; the other sources play."""

    def setup(world, audio):
        world.spawn(Transform(), AudioSource(clip=7))
        world.spawn(Transform(), AudioSource(clip=audio.clip(tone(300.0)), bus=9, loop=True))
        world.spawn(Transform(), _flat(audio.clip(tone(500.0)), loop=True))

    samples, _ = capture(tmp_path, setup, 10)
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2
    assert re.search(r"entity \d+ .*AudioSource.clip: 7 is not a clip of the Audio resource \(it has 2\)", lines[0])
    assert re.search(r"entity \d+ .*AudioSource.bus: 9 is not a bus \(there are 3: master, music, effects\)", lines[1])
    assert peak_frequency(samples[BLOCK:, 0]) == pytest.approx(500.0, rel=1e-3)


def test_a_negative_volume_is_refused_on_write():
    from ecs_engine.ecs.world import World

    with pytest.raises(Exception, match="volume"):
        World().spawn(AudioSource(volume=-1.0))


def test_audio_out_does_not_replace_another_kind_of_file(tmp_path):
    keep = tmp_path / "scene.json"
    keep.write_text('{"entities": []}')
    with pytest.raises(UsageError, match="not a WAV file"):
        check_outputs({"--audio-out": str(keep)}, {})
    check_outputs({"--audio-out": str(tmp_path / "new.wav")}, {})


def test_underruns_are_counted_and_reported_in_the_perf_lines():
    """A block asked for after the sound handed over before has run out is an underrun; the perf
    lines (and the Perf window) carry the count and the mixer's share of a core."""
    import time

    from ecs_engine.app.perf import PerfMonitor
    from ecs_engine.ecs.world import World

    world = World()
    audio = world.resources[Audio] = Audio("null")
    try:
        audio.output.device.stop()  # the device's thread no longer asks: this test does
        feed = audio.output._feed()
        next(feed)
        audio.output._runs_out = None
        feed.send(480)  # 10 ms handed over
        feed.send(480)  # at once: 20 ms ahead, no gap
        assert audio.underruns == 0
        time.sleep(0.06)  # the 20 ms ran out 40 ms ago
        feed.send(480)
        assert audio.underruns == 1
        perf = PerfMonitor()
        perf.gauges = lambda: world.resources
        line = perf.summary_line()
        assert "sound mix" in line and "underruns 1" in line
    finally:
        audio.close()


def test_a_streamed_clip_plays_the_file_and_loops_it(tmp_path):
    """A 0.5 s WAV loaded with stream=True, looped: the capture is the file's sound, its level
    and frequency, across the seam and on; the same clip decoded whole gives the same samples."""
    path = tmp_path / "music.wav"
    data = (tone(480.0, 0.5) * 0.5 * 32767).astype("<i2")
    with wave.open(str(path), "wb") as f:
        f.setnchannels(1), f.setsampwidth(2), f.setframerate(RATE), f.writeframes(data.tobytes())

    def setup(world, audio):
        world.resources["clips"] = (audio.load(path, stream=True), audio.load(path))
        world.spawn(Transform(), AudioSource(clip=world.resources["clips"][0], loop=True, spatial=False))

    samples, app = capture(tmp_path, setup, 60)
    streamed, whole = app.world.resources["clips"]
    assert streamed != whole and app.world.resources[Audio].load(path, stream=True) == streamed
    assert rms(samples[: RATE // 2]) == pytest.approx([0.5 / np.sqrt(2)] * 2, rel=1e-3)
    assert peak_frequency(samples[:, 0]) == pytest.approx(480.0, rel=1e-3)
    n = np.arange(len(samples))
    np.testing.assert_allclose(samples[:, 0], 0.5 * np.sin(2 * np.pi * 480.0 * n / RATE), atol=2e-4)
    with pytest.raises(UsageError, match="no such file"):
        app.world.resources[Audio].load(tmp_path / "gone.ogg", stream=True, strict=True)


def test_a_slow_frame_does_not_stop_the_sound():
    """While the game's thread runs Python for half a second (a slow frame), the sound device's
    thread goes on mixing: it gets the GIL at Python's switch interval, and nothing it needs is
    compiled or loaded there (a first mix on that thread held the sound for the whole 0.5 s)."""
    import time

    audio = Audio("null")
    try:
        audio.play(audio.clip(tone(440.0)), loop=True)
        time.sleep(0.1)
        start, mixed = time.perf_counter(), audio.mixer.frames_mixed
        spin = 0
        while time.perf_counter() - start < 0.5:
            for i in range(1000):
                spin += i
        busy = time.perf_counter() - start
        assert (audio.mixer.frames_mixed - mixed) / RATE > 0.5 * busy
    finally:
        audio.close()


def test_the_default_device_or_the_null_output_with_one_line():
    """Audio("device") opens the sound device where there is one; where there is none (CI, the
    GPU host) it says so in one line and plays into miniaudio's null output, and the game runs."""
    audio = Audio("device")
    try:
        fallback, backend = audio.output.fallback, audio.output.backend
        if fallback is None:
            assert backend != "Null"
        else:
            assert backend == "Null" and "\n" not in fallback
            assert fallback.startswith("no sound device") and fallback.endswith("sound goes to the null output")
        audio.play(audio.clip(tone(440.0, 0.05)))
    finally:
        audio.close()
