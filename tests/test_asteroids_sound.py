"""Asteroids' sound (demos/asteroids_sound.py) without a GPU or a sound device: a replayed run
(the seeded bot) writes the same capture twice; shots, explosions and the music are in it, each
where the game says."""

from __future__ import annotations

import numpy as np
from audio_scene import RATE, peak_frequency, rms
from test_asteroids import Meshes

from ecs_engine import World
from ecs_engine.audio import Audio
from ecs_engine.audio.outputs import read_wav
from ecs_engine.demos import asteroids
from ecs_engine.demos.asteroids_game import Game
from ecs_engine.demos.asteroids_sound import AsteroidsSound, music_clip, start_sound
from ecs_engine.ecs.timestep import FixedTimestep

FRAMES = 240


def _run(path, music: bool = True, seed: int = 1) -> tuple[np.ndarray, Game]:
    world = World()
    asteroids.build_world(world, Meshes().add, seed=seed, autoplay=True)
    audio = world.resources[Audio] = Audio(str(path))
    start_sound(world)
    if not music:
        audio.mute("music")
    schedule, clock = asteroids.schedule(autoplay=True, sound=True), FixedTimestep(1 / 60)
    for _ in range(FRAMES):
        schedule.run_frame(world, 1 / 60, clock)
    audio.close()
    assert world.resources[AsteroidsSound].shots_heard == world.resources[Game].shots
    return read_wav(path)[0], world.resources[Game]


def test_a_replayed_game_writes_the_same_sound_twice(tmp_path):
    first, game = _run(tmp_path / "a.wav")
    _run(tmp_path / "b.wav")
    assert (tmp_path / "a.wav").read_bytes() == (tmp_path / "b.wav").read_bytes()
    assert len(first) == FRAMES * RATE // 60 and game.shots > 0 and game.kills > 0
    _run(tmp_path / "c.wav", seed=2)
    assert (tmp_path / "c.wav").read_bytes() != (tmp_path / "a.wav").read_bytes()


def test_the_effects_and_the_music_are_heard(tmp_path):
    """With the music muted, the bot's shots and explosions are what is left, and loud enough;
    the music's loop starts and ends in silence, and each two-second bar is led by its bass note."""
    effects, game = _run(tmp_path / "fx.wav", music=False)
    assert game.shots > 5 and rms(effects).min() > 0.02
    assert np.abs(effects).max() < 1.0  # the mix stays within full scale
    loop = music_clip()
    assert abs(loop[0]) < 1e-3 and abs(loop[-1]) < 1e-3  # the loop's seam falls in silence
    bars = [loop[k * 2 * RATE : (k + 1) * 2 * RATE] for k in range(4)]
    assert [round(peak_frequency(bar)) for bar in bars] == [110, 87, 131, 98]  # A2 F2 C3 G2
