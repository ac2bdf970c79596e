"""Asteroids' sound: the engine's thrust, the shots, explosions by the asteroid's size, the ship
struck, and a music loop. Every sound is made here from numbers at start (no files, nothing to
license), the same on every run, so a replayed game writes the same `--audio-out` file.

- `start_sound(world)` makes the clips (the Audio resource's), the music's source and the
  listener on the camera;
- `SoundSystem` (in the fixed step, between the collisions and the damage they do) plays a shot
  where each new shot leaves the ship, an explosion where each hit asteroid is (larger ones
  lower and louder), a thud when the ship is struck, and keeps the ship's engine source playing
  as loud and as high as its thrust."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ecs_engine import World
from ecs_engine.audio import Audio
from ecs_engine.components import Camera, Transform
from ecs_engine.components.audio import MUSIC, AudioListener, AudioSource
from ecs_engine.ecs import System

from .asteroids_game import Asteroid, AsteroidHit, Game, Projectile, Ship, ShipControls, ShipHit

RATE = 48_000
# per asteroid size (0 small .. 2 large): the explosion's pitch and volume
EXPLOSION_PITCH, EXPLOSION_VOLUME = (1.5, 1.0, 0.6), (0.25, 0.45, 0.7)
# within this distance of the camera (which hangs 37 m from the ship) a sound is at full level;
# farther asteroids' explosions fade by inverse distance
HEARD_WHOLE = 40.0


def _seconds(s: float) -> np.ndarray:
    return np.arange(round(s * RATE)) / RATE


def _low_passed_loop(noise: np.ndarray, corner: float) -> np.ndarray:
    """`noise` through a one-pole-like low pass done in the frequency domain, which is circular:
    the result's end meets its start, so it loops without a seam."""
    spectrum = np.fft.rfft(noise)
    f = np.fft.rfftfreq(len(noise), 1 / RATE)
    out = np.fft.irfft(spectrum / (1.0 + (f / corner) ** 2), len(noise))
    return out / np.abs(out).max()


def thrust_clip(rng: np.random.Generator) -> np.ndarray:
    """A second of rumbling noise that loops."""
    return 0.6 * _low_passed_loop(rng.standard_normal(RATE), 220.0)


def shot_clip() -> np.ndarray:
    """A short falling zap."""
    t = _seconds(0.14)
    freq = 1700.0 * np.exp(-t * 9.0)  # falls to about a third
    phase = 2 * np.pi * np.cumsum(freq) / RATE
    tone = np.sin(phase) + 0.3 * np.sin(3 * phase)
    return 0.5 * tone * np.exp(-t * 22.0) * np.minimum(t * 2000.0, 1.0)


def explosion_clip(rng: np.random.Generator) -> np.ndarray:
    """A burst of low noise that dies away; played lower for larger asteroids."""
    t = _seconds(1.0)
    body = _low_passed_loop(rng.standard_normal(len(t)), 400.0)
    crack = rng.standard_normal(len(t)) * np.exp(-t * 40.0) * 0.3
    return 0.9 * (body * np.exp(-t * 4.5) + crack) * np.minimum(t * 400.0, 1.0)


def hit_clip() -> np.ndarray:
    """A dull thud: a low sine dropping in pitch."""
    t = _seconds(0.35)
    phase = 2 * np.pi * np.cumsum(90.0 * np.exp(-t * 3.0)) / RATE
    return 0.9 * np.sin(phase) * np.exp(-t * 9.0) * np.minimum(t * 1000.0, 1.0)


def music_clip() -> np.ndarray:
    """Eight seconds that loop: a bass line (A, F, C, G, two seconds each) and a plucked
    arpeggio in eighths over it; every note dies away within its own beat, so the loop's seam
    falls in silence."""
    beat = RATE // 4  # eighths at 120 bpm
    out = np.zeros(8 * RATE)
    bass = (110.0, 87.31, 130.81, 98.0)  # A2 F2 C3 G2
    for bar, root in enumerate(bass):
        for eighth in range(8):
            start = bar * 2 * RATE + eighth * beat
            t = np.arange(beat) / RATE
            fade = np.minimum(t * 500.0, 1.0) * np.clip((beat / RATE - t) * 200.0, 0.0, 1.0)
            if eighth % 4 == 0:  # the bass on each beat's first eighth, held a quarter of it
                note = np.sin(2 * np.pi * root * t) + 0.25 * np.sin(4 * np.pi * root * t)
                out[start : start + beat] += 0.35 * note * np.exp(-t * 3.0) * fade
            step = (1.0, 1.25, 1.5, 2.0)[eighth % 4]  # root, third, fifth, octave
            pluck = np.sin(2 * np.pi * root * 4 * step * t) * np.exp(-t * 14.0)
            out[start : start + beat] += 0.12 * pluck * fade
    return out


@dataclass
class AsteroidsSound:
    """The game's clips (handles of the Audio resource) and what SoundSystem keeps between steps."""

    clips: dict[str, int]
    shots_heard: int = 0
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(11))


def start_sound(world: World) -> None:
    """The clips, the music and the listener (on the camera). Needs the Audio resource."""
    audio = world.resources[Audio]
    rng = np.random.default_rng(7)  # the sounds' own: the game's random numbers stay the game's
    made = {
        "thrust": thrust_clip(rng),
        "shot": shot_clip(),
        "explosion": explosion_clip(rng),
        "hit": hit_clip(),
        "music": music_clip(),
    }
    clips = {name: audio.clip(samples, name=f"asteroids {name}") for name, samples in made.items()}
    world.resources[AsteroidsSound] = AsteroidsSound(clips)
    world.spawn(AudioSource(clip=clips["music"], loop=True, spatial=False, bus=MUSIC, volume=0.5), Transform())
    for batch in world.query(Camera, without=(AudioListener,)):
        for camera in batch.entities:
            world.add(int(camera), AudioListener())


class SoundSystem(System):
    """See the module."""

    def __init__(self) -> None:
        super().__init__(
            reads=[AsteroidHit, ShipHit, Asteroid, Projectile, Game, ShipControls, Ship, Transform],
            writes=[AudioSource],
            name="sound",
        )

    def run(self, world: World, dt: float) -> None:
        sound, audio = world.resources.get(AsteroidsSound), world.resources.get(Audio)
        if sound is None or audio is None:
            return
        game, controls = world.resources[Game], world.resources[ShipControls]
        clips = sound.clips
        if game.shots < sound.shots_heard:  # a restart counts from 0 again
            sound.shots_heard = 0
        fired, sound.shots_heard = game.shots - sound.shots_heard, game.shots
        ship_at = None
        for batch in world.query(Transform, with_=(Ship,), write=()):
            if len(batch):
                ship_at = batch[Transform].position[0].copy()
        if fired and ship_at is not None:
            for _ in range(fired):
                pitch = float(sound.rng.uniform(0.94, 1.06))
                audio.play(clips["shot"], at=ship_at, pitch=pitch, volume=0.6, min_distance=HEARD_WHOLE)
        hits = world.events(AsteroidHit).read()
        for rock in hits.asteroid if len(hits) else ():
            size = int(world.get(int(rock), Asteroid).size)
            at = world.get(int(rock), Transform).position
            volume = EXPLOSION_VOLUME[size]
            audio.play(clips["explosion"], at=at, pitch=EXPLOSION_PITCH[size], volume=volume, min_distance=HEARD_WHOLE)
        for _ in world.events(ShipHit).read():
            audio.play(clips["hit"], volume=0.8)
        self._engine(world, clips["thrust"], 0.0 if game.over else abs(float(controls.thrust)))

    @staticmethod
    def _engine(world: World, clip: int, thrust: float) -> None:
        """The ship's engine: a looping source on the ship, as loud and as high as its thrust."""
        for batch in world.query(Ship, without=(AudioSource,), write=()):
            for ship in batch.entities:  # a new ship (a start, a restart): its engine
                world.add(int(ship), AudioSource(clip=clip, loop=True, volume=0.0, min_distance=HEARD_WHOLE))
        for batch in world.query(AudioSource, with_=(Ship,)):
            source = batch[AudioSource]
            source.volume = 0.7 * thrust
            source.pitch = 0.8 + 0.5 * math.sqrt(thrust)
