"""Scaling scene: N moving, spinning entities (mostly cubes, some torus knots) in a box around
the camera's view, with orbiting point lights. `--entities` sets N (up to millions)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import AngularVelocity, Mesh, Transform, Velocity
from ecs_engine.render import DEFAULT_MODEL, MeshData, cube_mesh, load_mesh, normalized

from .scene_kit import add_camera, add_orbiting_lights

KNOT_SHARE = (
    0.001  # the knot has 1,024x the cube's triangles: at 0.1% the knots and cubes weigh about the same on the GPU
)


def build(
    world: World, add_mesh: Callable[[MeshData], int], path: str | None = None, entities: int = 10_000, seed: int = 7
) -> None:
    cube = add_mesh(cube_mesh())
    knot = add_mesh(normalized(load_mesh(DEFAULT_MODEL), size=1.0))
    rng = np.random.default_rng(seed)
    n = int(entities)
    half = max(10.0, np.cbrt(n) * 1.2)  # about one entity per 1.7 units of space each way
    handles = np.where(rng.random(n) < KNOT_SHARE, knot, cube).astype(np.uint32)
    world.spawn_batch(
        n,
        Transform(
            position=rng.uniform(-half, half, size=(n, 3)),
            rotation=rng.normal(size=(n, 4)),
            scale=rng.uniform(0.4, 1.0, size=(n, 1)).repeat(3, axis=1),
        ),
        Velocity(linear=rng.normal(scale=0.5, size=(n, 3))),
        AngularVelocity(angular=rng.normal(size=(n, 3))),
        Mesh(handle=handles, material=rng.integers(0, 6, size=n, dtype=np.uint32)),
    )
    add_camera(world, eye=(0.0, half * 0.4, half * 1.6), target=(0.0, 0.0, 0.0), move_speed=half * 0.3)
    add_orbiting_lights(world, radius=half * 0.8, height=half * 0.5, intensity=half * half * 0.4)
