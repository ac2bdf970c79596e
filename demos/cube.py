"""The seed's simple scene: one cube in the middle of the screen, six orbiting lights."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.render import MeshData, cube_mesh

from .scene_kit import add_camera, add_orbiting_lights


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    cube = add_mesh(cube_mesh())
    angle = np.radians(30.0)
    world.spawn(Transform(rotation=(0.0, np.sin(angle / 2), 0.0, np.cos(angle / 2))), Mesh(handle=cube, material=0))
    add_camera(world, eye=(0.0, 1.0, 2.6), target=(0.0, 0.0, 0.0))
    add_orbiting_lights(world, radius=1.3, height=0.6, intensity=0.8)
