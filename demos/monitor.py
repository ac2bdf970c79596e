"""Render to texture: a room (a floor, a few boxes, a light) with a monitor on a stand, whose screen
shows what a second camera sees: a spinning magenta cube far off in a studio of its own. The
second camera draws into RenderTexture "monitor" (components/camera_views.py) and only sees
layer 1 (RenderLayers), where the cube is; the room's camera sees layer 0 alone, so the cube is
nowhere in the room but on the screen, whose material samples the texture by the name
(Textures.render_target: render/frame/texture_views.py draws it each frame before the window)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import (
    AngularVelocity,
    Camera,
    DirectionalLight,
    Mesh,
    PointLight,
    RenderLayers,
    RenderTexture,
    Transform,
)
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, MeshData, cube_mesh, materials

from .scene_kit import add_camera

SCREEN = (128, 96)  # the monitor's picture in pixels: 4:3, as the screen's box
STUDIO = np.array([40.0, 0.0, 0.0])  # where the spinning cube is, far from the room
LAYER = 0b10  # layer 1: the studio's (the room is on layer 0, the default)


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    cube = add_mesh(cube_mesh())
    library = materials(world)
    floor = library.add(Material("floor", "lambert", (0.55, 0.55, 0.6, 1.0)))
    wood = library.add(Material("wood", "blinn_phong", (0.6, 0.4, 0.25, 1.0), shininess=16.0, specular=0.2))
    frame = library.add(Material("frame", "lambert", (0.08, 0.08, 0.09, 1.0)))
    picture = library.textures.render_target("monitor", *SCREEN)
    screen = library.add(Material("screen", "unlit", (1.0, 1.0, 1.0, 1.0), base_color_texture=picture))
    magenta = library.add(Material("magenta", "lambert", (0.9, 0.05, 0.8, 1.0), emissive=(0.25, 0.0, 0.22)))

    world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(14.0, 1.0, 14.0)), Mesh(handle=cube, material=floor))
    for x, z, s in ((-3.2, 0.5, 0.9), (2.8, 1.2, 0.7), (-1.8, 2.6, 0.5)):
        world.spawn(Transform(position=(x, s / 2, z), scale=(s, s, s)), Mesh(handle=cube, material=wood))
    # the monitor: a stand, a dark frame and the screen just in front of it (4:3, as the picture)
    world.spawn(Transform(position=(0.0, 0.6, -3.0), scale=(0.3, 1.2, 0.3)), Mesh(handle=cube, material=frame))
    world.spawn(Transform(position=(0.0, 2.2, -3.05), scale=(3.4, 2.6, 0.12)), Mesh(handle=cube, material=frame))
    world.spawn(Transform(position=(0.0, 2.2, -2.98), scale=(3.2, 2.4, 0.02)), Mesh(handle=cube, material=screen))
    world.spawn(Transform(rotation=look_rotation((-0.4, -1.0, -0.6))), DirectionalLight(illuminance=1.2))
    world.spawn(Transform(position=(2.0, 3.5, 2.0)), PointLight(color=(1.0, 0.9, 0.75), intensity=8.0, radius=12.0))
    add_camera(world, eye=(3.0, 2.6, 5.5), target=(0.0, 1.8, -3.0))

    # the studio: the cube spinning on layer 1, and the camera that draws it into "monitor"
    world.spawn(
        Transform(position=STUDIO, scale=(1.2, 1.2, 1.2)),
        Mesh(handle=cube, material=magenta),
        AngularVelocity(angular=(0.5, 1.1, 0.3)),
        RenderLayers(mask=LAYER),
    )
    eye = STUDIO + (0.0, 1.2, 3.6)
    world.spawn(
        Transform(position=eye, rotation=look_rotation(STUDIO - eye)),
        Camera(fov_y=math.radians(45.0), near=0.05),
        RenderTexture(name="monitor", width=SCREEN[0], height=SCREEN[1]),
        RenderLayers(mask=LAYER),
    )
