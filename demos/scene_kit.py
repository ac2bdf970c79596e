"""Pieces the seed's scenes share: a fly camera aimed at a point, six orbiting coloured lights."""

from __future__ import annotations

import math

import numpy as np

from ecs_engine import World
from ecs_engine.components import Camera, FlyCamera, Orbit, PointLight, Transform
from ecs_engine.maths.camera import yaw_pitch_quat

# The seed's light colours: one per light, six around the scene.
LIGHT_COLORS = [(1.0, 0.1, 0.1), (0.1, 0.1, 1.0), (0.1, 1.0, 0.1), (1.0, 1.0, 0.1), (0.1, 1.0, 1.0), (1.0, 1.0, 1.0)]


def add_camera(
    world: World, eye: tuple[float, float, float], target: tuple[float, float, float], move_speed: float = 3.0
) -> int:
    eye_a, target_a = np.asarray(eye, dtype=np.float64), np.asarray(target, dtype=np.float64)
    d = target_a - eye_a
    yaw = math.atan2(-d[0], -d[2])
    pitch = math.atan2(d[1], math.hypot(d[0], d[2]))
    return world.spawn(
        Transform(position=eye_a, rotation=yaw_pitch_quat(yaw, pitch)),
        Camera(fov_y=math.radians(50.0), near=0.05),
        FlyCamera(yaw=yaw, pitch=pitch, move_speed=move_speed),
    )


def add_orbiting_lights(
    world: World,
    radius: float,
    height: float,
    intensity: float,
    center: tuple[float, float, float] = (0.0, 0.0, 0.0),
    speed: float = 0.6,
) -> np.ndarray:
    n = len(LIGHT_COLORS)
    phase = np.arange(n) * (2 * math.pi / n)
    return world.spawn_batch(
        n,
        Transform(),
        Orbit(center=center, radius=radius, angular_speed=speed, phase=phase, height=height),
        PointLight(color=np.array(LIGHT_COLORS, dtype=np.float32), intensity=intensity, radius=0.0),
    )
