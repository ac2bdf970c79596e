"""Many lights: N small coloured point and spot lights (default 1,024; `--lights N`) wandering
over a floor and a field of spheres and cubes. With more than a few dozen bounded lights the
renderer clusters them (render/lighting/clusters.py); `--light-culling loop` draws the same image
with every fragment looping over every light, for comparison. A dim directional light keeps the
scene readable where no small light reaches.

"Small" scales with the count: a light's reach is REACH_SPACINGS times the mean spacing of the
lights over the floor, and its intensity follows the reach squared, so any count lights the floor
about as brightly and each point of the floor is reached by about the same number of lights
(~20). That is what makes light counts comparable in `bench lights`: with a fixed reach, 16 times
the lights would also mean 16 times the lights per pixel, a different scene rather than more of
the same one."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import DirectionalLight, Mesh, Orbit, PointLight, SpotLight, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, MeshData, cube_mesh, materials, plane_mesh, sphere_mesh

from .scene_kit import add_camera

DEFAULT_LIGHTS = 1024
FIELD = 40.0  # the floor's side
SPOT_SHARE = 8  # one light in 8 is a spot light
REACH_SPACINGS = 2.0  # a light's radius, in mean spacings between lights


def build(
    world: World, add_mesh: Callable[[MeshData], int], path: str | None = None, lights: int = DEFAULT_LIGHTS
) -> None:
    rng = np.random.default_rng(7)
    library = materials(world)
    floor = library.add(Material("floor", "cook_torrance", (0.5, 0.5, 0.52, 1.0), roughness=0.6))
    looks = [
        library.add(Material("clay", "lambert", (0.8, 0.75, 0.7, 1.0))),
        library.add(Material("metal", "cook_torrance", (0.9, 0.9, 0.92, 1.0), metallic=1.0, roughness=0.3)),
        library.add(Material("plastic", "blinn_phong", (0.3, 0.5, 0.8, 1.0), shininess=64.0, specular=0.5)),
    ]
    world.spawn(Transform(scale=(FIELD, 1.0, FIELD)), Mesh(handle=add_mesh(plane_mesh(1.0, 40)), material=floor))
    shapes = [add_mesh(sphere_mesh(32, 16)), add_mesh(cube_mesh())]
    grid = np.arange(-FIELD / 2 + 2, FIELD / 2 - 1, 3.0)
    for i, x in enumerate(grid):
        for j, z in enumerate(grid):
            shape = shapes[(i + j) % 2]
            size = rng.uniform(0.6, 1.3)
            world.spawn(
                Transform(position=(x, size / 2, z), scale=(size, size, size)),
                Mesh(handle=shape, material=looks[(i * 7 + j) % len(looks)]),
            )
    world.spawn(Transform(rotation=look_rotation((0.3, -1.0, -0.5))), DirectionalLight(illuminance=0.04))
    add_lights(world, rng, lights)
    add_camera(world, eye=(0.0, 14.0, 24.0), target=(0.0, 0.0, 0.0), move_speed=8.0)


def add_lights(world: World, rng: np.random.Generator, n: int) -> None:
    reach = min(REACH_SPACINGS * FIELD / math.sqrt(max(n, 1)), FIELD)
    power = (reach / 2.5) ** 2  # the lights of the default count have a reach of about 2.5
    spots = n // SPOT_SHARE
    points = n - spots
    hue = rng.uniform(0.0, 1.0, n)
    colors = np.clip(np.abs(((hue[:, None] * 6 + np.array([0.0, 4.0, 2.0])) % 6) - 3) - 1, 0, 1) * 0.8 + 0.2
    if points:
        centers = np.c_[
            rng.uniform(-FIELD / 2, FIELD / 2, points), np.zeros(points), rng.uniform(-FIELD / 2, FIELD / 2, points)
        ]
        world.spawn_batch(
            points,
            Transform(),
            Orbit(
                center=centers,
                radius=rng.uniform(0.2, 1.0, points) * reach,
                angular_speed=rng.uniform(-1.2, 1.2, points),
                phase=rng.uniform(0, 2 * math.pi, points),
                height=rng.uniform(0.4, 1.6, points),
            ),
            PointLight(
                color=colors[:points].astype(np.float32),
                intensity=rng.uniform(0.6, 2.0, points) * power,
                radius=reach * rng.uniform(0.6, 1.4, points),
            ),
        )
    for k in range(spots):
        x, z = rng.uniform(-FIELD / 2, FIELD / 2, 2)
        aim = (rng.uniform(-0.4, 0.4), -1.0, rng.uniform(-0.4, 0.4))
        world.spawn(
            Transform(position=(x, min(rng.uniform(2.5, 4.0), reach), z), rotation=look_rotation(aim)),
            SpotLight(
                color=tuple(colors[points + k]),
                intensity=rng.uniform(6.0, 12.0) * power,
                radius=2.4 * reach,
                inner_angle=0.25,
                outer_angle=0.5,
            ),
        )
