"""Double-sided materials: back faces drawn and lit with the reversed normal; single-sided ones in
the same scene still show nothing from behind (culling is off, the fragment shader drops them)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import plane_mesh
from ecs_engine.render.assets.textures import linear_to_srgb

W, H = 96, 48
FACING_MINUS_Z = (-math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # +Y (the normal) -> -Z


def render(gpu, sides: tuple[bool, bool]) -> np.ndarray:
    """Two planes facing away from the camera (it sees their backs), left and right, lit from the
    camera's side by a light shining along -Z."""
    world = World()
    mesh = gpu.meshes.add(plane_mesh(1.0))
    for x, double in zip((-0.6, 0.6), sides):
        m = materials(world).add(Material("m", "lambert", (0.5, 0.5, 0.5, 1.0), double_sided=double))
        world.spawn(Transform(position=(x, 0.0, 0.0), rotation=FACING_MINUS_Z), Mesh(handle=mesh, material=m))
    world.spawn(Transform(position=(0.0, 0.0, 1.3)), Camera(fov_y=math.radians(60.0), near=0.05))
    world.spawn(Transform(rotation=look_rotation((0.0, 0.0, -1.0))), DirectionalLight(illuminance=1.0))
    return render_world(gpu, world, ambient=(1.0, 1.0, 1.0, 0.0))


@pytest.mark.parametrize("sides", [(False, False), (True, False), (True, True)])
def test_back_faces_show_only_for_double_sided_materials(sides):
    with headless_gpu(W, H) as gpu:
        img = render(gpu, sides)
    background = img[0, 0]
    lit = round(float(linear_to_srgb(np.array(0.5))) * 255)  # the reversed normal faces the light
    for x, double in zip((W // 4, 3 * W // 4), sides):
        pixel = img[H // 2, x]
        if double:
            assert np.abs(pixel - lit).max() <= 1, pixel
        else:
            assert (pixel == background).all(), pixel


def test_double_sided_is_checked_and_imported():
    with pytest.raises(ValueError, match="double_sided"):
        Material("m", double_sided="yes")
    assert Material("m", double_sided=True).row()["kind"][2] == 1
