"""Split screen: the seed's 100-cube grid under its six orbiting lights, seen by two players'
cameras, each drawing into half of the window (components/camera_views.py: a Viewport per camera).
The left one is the fly camera (keys and mouse steer it); the right one looks from the other side.
A third, small camera with a higher order draws a picture-in-picture view from above in the
right half's corner, over it."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import Camera, Transform, Viewport
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import MeshData, cube_mesh

from .grid100 import spawn_grid
from .scene_kit import add_camera, add_orbiting_lights


def _look(eye: tuple[float, float, float], target: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Transform:
    d = np.asarray(target, np.float64) - np.asarray(eye, np.float64)
    return Transform(position=eye, rotation=look_rotation(d))


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    spawn_grid(world, add_mesh(cube_mesh()))
    add_orbiting_lights(world, radius=5.0, height=3.5, intensity=6.0)
    left = add_camera(world, eye=(7.0, 5.5, 9.0), target=(0.0, -0.3, 0.0), move_speed=6.0)
    world.add(left, Viewport(x=0.0, y=0.0, width=0.5, height=1.0))
    world.spawn(_look((-8.0, 3.0, -9.0)), Camera(fov_y=math.radians(50.0), near=0.05), Viewport(x=0.5, width=0.5))
    world.spawn(
        _look((0.0, 14.0, 0.01)),
        Camera(fov_y=math.radians(45.0), near=0.05),
        Viewport(x=0.72, y=0.04, width=0.25, height=0.3, order=1),
    )
