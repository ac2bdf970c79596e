"""A crowd of animated characters (demos/character.py's humanoid, a skinned glTF scene spawned
many times): each strolls about, now standing, now walking, now running, and plays idle, walk or
run by its speed, cross-fading when that changes (animation/player.py's fades), its gait's
playback following its speed. The sun casts their shadows on the ground.

`ecs-engine demo animation` (--entities: how many characters, 200 by default here)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine import World
from ecs_engine.animation.player import AnimationSystem
from ecs_engine.components import DirectionalLight, Mesh, Shadow, Transform
from ecs_engine.components.animation import AnimationPlayer
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.ecs.schema import Component, Field
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import MeshData, cube_mesh
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import Material, materials

from .character import CLIPS, character_file
from .scene_kit import add_camera

CHARACTERS = 200
SPACING = 2.5  # m between characters at the start
SPEEDS = (0.0, 1.3, 3.4)  # m/s a character aims for: standing, walking, running
GAIT = (1.0, 1.3, 3.4)  # m/s the clips' steps cover at speed 1 (idle: any)
BANDS = (0.35, 2.2)  # below the first: idle; below the second: walk; else run
FADE = 0.3  # s
ACCELERATION = 2.5  # m/s^2
AREA = 30.0  # m: they turn back towards the middle beyond this distance


class Stroll(Component):
    """A character's wandering: its speed now and the speed it aims for, its heading (radians
    about +Y), the seconds until it changes its mind, and its gait band (0 idle, 1 walk, 2 run)."""

    speed = Field(np.float64, default=0.0, finite=True)
    goal = Field(np.float64, default=0.0, finite=True)
    heading = Field(np.float64, default=0.0, finite=True)
    change = Field(np.float64, default=0.0, finite=True)
    band = Field(np.int32, default=0)


@dataclass
class CrowdClips:
    """Resource: the clip handles of idle, walk and run (by band)."""

    handles: tuple[int, ...]


class StrollSystem(System):
    """Moves each character along its heading at its speed, picks new goals now and then, and
    cross-fades its player to the clip of its gait band when the band changes."""

    def __init__(self, seed: int = 1) -> None:
        super().__init__(
            reads=[CrowdClips], writes=[Stroll, Transform, AnimationPlayer], name="stroll", run_if=any_with(Stroll)
        )
        self.rng = np.random.default_rng(seed)

    def run(self, world: Any, dt: float) -> None:
        handles = np.array(world.resources[CrowdClips].handles, np.int32)
        for batch in world.query(Stroll, Transform, AnimationPlayer):
            s, t, p = batch[Stroll], batch[Transform], batch[AnimationPlayer]
            n = len(batch)
            s.change = s.change - dt
            due = s.change <= 0.0
            if due.any():
                s.goal = np.where(due, np.array(SPEEDS)[self.rng.integers(0, 3, n)], s.goal)
                s.heading = np.where(due, s.heading + self.rng.uniform(-1.2, 1.2, n), s.heading)
                s.change = np.where(due, self.rng.uniform(2.0, 6.0, n), s.change)
            far = np.hypot(t.position[:, 0], t.position[:, 2]) > AREA
            home = np.arctan2(-t.position[:, 0], -t.position[:, 2])
            s.heading = np.where(far, home, s.heading)
            step = np.clip(s.goal - s.speed, -ACCELERATION * dt, ACCELERATION * dt)
            s.speed = s.speed + step
            forward = np.c_[np.sin(s.heading), np.zeros(n), np.cos(s.heading)]
            t.position = t.position + forward * (s.speed * dt)[:, None]
            t.rotation = np.c_[np.zeros(n), np.sin(s.heading / 2), np.zeros(n), np.cos(s.heading / 2)]
            band = np.where(s.speed < BANDS[0], 0, np.where(s.speed < BANDS[1], 1, 2)).astype(np.int32)
            changed = band != s.band
            if changed.any():  # cross-fade from what it plays to its band's clip
                p.from_clip = np.where(changed, p.clip, p.from_clip)
                p.from_time = np.where(changed, p.time, p.from_time)
                p.fade = np.where(changed, FADE, p.fade)
                p.faded = np.where(changed, 0.0, p.faded)
                p.clip = np.where(changed, handles[band], p.clip)
                p.time = np.where(changed, 0.0, p.time)
                s.band = band
            # the gait's playback follows the speed, so that feet keep pace with the ground
            p.speed = np.where(band == 0, 1.0, np.maximum(s.speed, 0.3) / np.array(GAIT)[band])


def build(
    world: World, add_mesh: Callable[[MeshData], int], path: str | None = None, entities: int = CHARACTERS
) -> None:
    from ecs_engine.user_dirs import cache_home

    n = max(1, int(entities))
    ground = materials(world).add(Material("ground", "lambert", (0.3, 0.34, 0.28, 1.0)))
    world.spawn(
        Transform(position=(0.0, -0.1, 0.0), scale=(2.5 * AREA, 0.2, 2.5 * AREA)),
        Mesh(handle=add_mesh(cube_mesh()), material=ground),
    )
    try:
        folder = cache_home() / "ecs_engine" / "demos"
    except RuntimeError:  # no home directory
        folder = Path.cwd() / ".ecs_engine-demos"
    scene = load_gltf(character_file(folder), add_mesh, materials(world))
    handles = scene.clip_handles(world)
    world.resources[CrowdClips] = CrowdClips(tuple(handles[name] for name in CLIPS))
    side = math.ceil(math.sqrt(n))
    k = np.arange(n)
    at = np.c_[(k % side - (side - 1) / 2) * SPACING, np.zeros(n), (k // side - (side - 1) / 2) * SPACING]
    rng = np.random.default_rng(3)
    headings = rng.uniform(-math.pi, math.pi, n)
    turns = np.c_[np.zeros(n), np.sin(headings / 2), np.zeros(n), np.cos(headings / 2)]
    roots = scene.spawn_many(world, n, at, turns, play="idle")
    phases = rng.uniform(0.0, CLIPS["idle"], n)
    world.set(roots, AnimationPlayer(clip=handles["idle"], time=phases))
    world.add(roots, Stroll(heading=headings, change=rng.uniform(0.0, 2.0, n)))
    extent = side * SPACING
    add_camera(world, eye=(0.0, 0.35 * extent + 3.0, 0.55 * extent + 5.0), target=(0.0, 0.8, 0.0), move_speed=8.0)
    sun = look_rotation((0.45, -1.0, -0.35))
    world.spawn(Transform(rotation=sun), DirectionalLight(illuminance=1.4), Shadow(cascades=3, distance=extent + 20.0))


def systems() -> list[tuple[str, System]]:
    """What the scene runs besides the demo scenes' schedule: the strolling, then the clips."""
    return [("update", StrollSystem()), ("update", AnimationSystem())]
