"""The seed's intermediate scene: a 4 x 5 x 5 grid of 100 cubes, six orbiting lights."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.render import MeshData, cube_mesh

from .scene_kit import add_camera, add_orbiting_lights

SPACING = 1.5


def grid_positions() -> np.ndarray:
    x, y, z = np.meshgrid(np.arange(5), np.arange(4), np.arange(5), indexing="ij")
    cells = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1).astype(np.float64)
    return (cells - cells.mean(axis=0)) * SPACING


def spawn_grid(world: World, cube: int) -> None:
    """The 100 cubes (mesh `cube`), each with one of the six palette materials in turn."""
    pos = grid_positions()
    n = len(pos)
    world.spawn_batch(
        n, Transform(position=pos, scale=(0.7, 0.7, 0.7)), Mesh(handle=cube, material=np.arange(n, dtype=np.uint32) % 6)
    )


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    spawn_grid(world, add_mesh(cube_mesh()))
    add_camera(world, eye=(7.0, 5.5, 9.0), target=(0.0, -0.3, 0.0), move_speed=6.0)
    add_orbiting_lights(world, radius=5.0, height=3.5, intensity=6.0)
