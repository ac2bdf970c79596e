"""Shadows (issue 15): a ground box 40 x 1 x 40 whose top face is at y = 0, a unit cube centred at
(0, 1, 0) under one directional light shining straight down, seen from (0, 8, 8); away from the
centre a spot light throws a pillar's shadow across the ground, and a point light's six cube
faces throw two boxes' shadows away from it.
`shadows=False` (`--no-shadows`) builds the same scene with no Shadow on any light."""

from __future__ import annotations

from collections.abc import Callable

from ecs_engine import World
from ecs_engine.components import DirectionalLight, Mesh, PointLight, Shadow, SpotLight, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, MeshData, cube_mesh, materials

from .scene_kit import add_camera


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None, shadows: bool = True) -> None:
    cube = add_mesh(cube_mesh())
    library = materials(world)
    ground = library.add(Material("ground", "lambert", (0.7, 0.7, 0.7, 1.0)))
    stone = library.add(Material("stone", "blinn_phong", (0.8, 0.45, 0.3, 1.0), shininess=32.0, specular=0.3))
    world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(40.0, 1.0, 40.0)), Mesh(handle=cube, material=ground))
    world.spawn(Transform(position=(0.0, 1.0, 0.0)), Mesh(handle=cube, material=stone))
    world.spawn(Transform(position=(-6.0, 1.5, -1.0), scale=(0.6, 3.0, 0.6)), Mesh(handle=cube, material=stone))
    for x, z in ((6.0, -2.0), (7.5, 0.5)):
        world.spawn(Transform(position=(x, 0.5, z)), Mesh(handle=cube, material=stone))
    cast = [Shadow()] if shadows else []
    world.spawn(Transform(rotation=look_rotation((0.0, -1.0, 0.0))), DirectionalLight(illuminance=0.45), *cast)
    world.spawn(
        Transform(position=(-3.0, 5.0, 1.0), rotation=look_rotation((-0.55, -1.0, -0.4))),
        SpotLight(color=(1.0, 0.85, 0.6), intensity=40.0, radius=14.0, inner_angle=0.35, outer_angle=0.5),
        *([Shadow(resolution=1024)] if shadows else []),
    )
    world.spawn(
        Transform(position=(6.8, 2.5, -0.7)),
        PointLight(color=(0.6, 0.75, 1.0), intensity=6.0, radius=9.0),
        *([Shadow(resolution=512)] if shadows else []),
    )
    add_camera(world, (0.0, 8.0, 8.0), (0.0, 0.0, 0.0))
