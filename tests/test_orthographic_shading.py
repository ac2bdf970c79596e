"""An orthographic camera's view direction (issue 33): every ray of an orthographic view is
parallel, so every view-dependent term (specular, Fresnel, Oren-Nayar, environment reflections)
takes the camera's axis, never the direction to the camera's position, which only places its
near plane. Moving such a camera back along its own axis leaves the projection, and so the
image, as it was: in every shading path (forward, clustered, deferred, weighted blending, the
textured variants, the environment's reflections)."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.components import ORTHOGRAPHIC, Camera, DirectionalLight, Environment, Mesh, PointLight, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh, sphere_mesh
from ecs_engine.render.assets.textures import Texture

W, H = 96, 64
AXIS = np.array([0.35, -0.55, -1.0]) / np.linalg.norm([0.35, -0.55, -1.0])  # where the camera looks
TARGET = np.array([0.3, 0.7, 0.3])

LOOKS = [
    dict(model="cook_torrance", base_color=(0.8, 0.3, 0.2, 1.0), roughness=0.25),
    dict(model="cook_torrance", base_color=(0.9, 0.8, 0.5, 1.0), roughness=0.4, metallic=1.0),
    dict(model="blinn_phong", base_color=(0.2, 0.5, 0.8, 1.0), shininess=48.0, specular=0.8),
    dict(model="phong", base_color=(0.3, 0.7, 0.3, 1.0), shininess=24.0, specular=0.8),
    dict(model="oren_nayar", base_color=(0.7, 0.7, 0.7, 1.0), roughness=0.8),
]


def scene(gpu, back: float, textured: bool = False, blended: bool = False, environment: bool = False) -> World:
    """Five spheres in a row on a ground box (a material each, specular but for Oren-Nayar), a
    point light and a sun; the camera orthographic, 6 units from the target plus `back`."""
    world = World()
    sphere, cube = gpu.meshes.add(sphere_mesh(32, 16)), gpu.meshes.add(cube_mesh())
    library = materials(world)
    extra: dict = {}
    if textured:  # the _textured shader variants: a mild checker on the spheres' base colour
        px = np.full((8, 8, 4), 255, np.uint8)
        i, j = np.mgrid[0:8, 0:8]
        px[..., :3] = np.where(((i + j) % 2 == 0)[..., None], 255, 200)
        extra["base_color_texture"] = library.textures.add(Texture("checker", px))
    for k, look in enumerate(LOOKS):
        handle = library.add(Material(f"look {k}", **look, **extra))
        world.spawn(Transform(position=(1.1 * (k - 2), 0.5, 0.0)), Mesh(handle=sphere, material=handle))
    if blended:
        glass = library.add(
            Material("tinted", "cook_torrance", (0.3, 0.6, 0.9, 0.5), roughness=0.2, alpha_mode="blend")
        )
        world.spawn(Transform(position=(0.5, 0.5, 1.1)), Mesh(handle=sphere, material=glass))
    if environment:
        faces = np.broadcast_to(
            np.array([(1, 0.2, 0.2), (0.2, 1, 0.2), (0.2, 0.2, 1), (1, 1, 0.3), (0.3, 1, 1), (1, 0.3, 1)], np.float32)[
                :, None, None, :
            ],
            (6, 16, 16, 3),
        ).copy()
        world.resources[Environment] = Environment(faces, intensity=0.3, sky=False)
        mirror = library.add(Material("mirror", "cook_torrance", (0.5, 0.5, 0.5, 1.0), roughness=0.1, reflectivity=0.6))
        world.spawn(Transform(position=(-0.5, 0.5, 1.1)), Mesh(handle=sphere, material=mirror))
    ground = library.add(Material("ground", "blinn_phong", (0.5, 0.5, 0.5, 1.0), shininess=16.0, specular=0.5))
    world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(12.0, 1.0, 6.0)), Mesh(handle=cube, material=ground))
    world.spawn(Transform(position=(1.0, 2.0, 2.0)), PointLight(intensity=8.0, radius=12.0))
    world.spawn(Transform(rotation=look_rotation((-0.4, -1.0, -0.5))), DirectionalLight(illuminance=0.6))
    eye = TARGET - AXIS * (6.0 + back)
    world.spawn(
        Transform(position=tuple(eye), rotation=look_rotation(tuple(AXIS))),
        Camera(projection=ORTHOGRAPHIC, height=3.8, near=0.5, far=20.0 + back),
    )
    return world


@pytest.mark.parametrize(
    ("settings", "options"),
    [
        (dict(light_culling="loop"), {}),
        (dict(light_culling="loop"), dict(textured=True)),
        (dict(light_culling="clustered"), {}),
        (dict(light_culling="clustered"), dict(textured=True)),
        (dict(light_culling="deferred"), {}),
        (dict(light_culling="deferred"), dict(textured=True)),
        (dict(light_culling="loop"), dict(blended=True)),  # sorted blending: drawn forward, set aside
        (dict(light_culling="deferred", transparency="weighted"), dict(blended=True)),  # weighted (OIT)
        (dict(light_culling="loop"), dict(environment=True)),  # mirrors: the environment's reflection
    ],
    ids=["forward", "forward-textured", "clustered", "clustered-textured", "deferred", "deferred-textured",
         "sorted-blend", "weighted-blend", "environment"],
)  # fmt: skip
def test_moving_an_orthographic_camera_back_changes_nothing(settings, options):
    with headless_gpu(W, H) as gpu:
        near, far = (render_world(gpu, scene(gpu, back, **options), **settings) for back in (0.0, 4.0))
    assert np.abs(near - far).max() <= 1, np.abs(near - far).max()
    assert near.std() > 20  # the scene is in view (not a blank image that cannot change)
