"""Which side of a caster a shadow map holds (issue 33): the side facing the light, under every
kind of light and in every render path. A single-sided plane facing the light casts; one facing
away casts nothing (it is not there from the light's side, as it is not from the camera's);
a double-sided one casts both ways; and a closed caster's point-light shadow reaches its foot.
The point lights' cube faces were the spec's mirror images, so their maps held the far sides."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world
from pixel_rays import pixel_rays

from ecs_engine import World
from ecs_engine.components import DirectionalLight, Mesh, PointLight, Shadow, SpotLight, Transform
from ecs_engine.components.shadow import SHADOW_HARD, SHADOW_PCF
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh, plane_mesh

W, H = 128, 80
LIGHT = np.array([0.3, 3.0, 0.2])  # the point and spot lights (the issue's)
SUN = np.array([-0.1, -1.0, 0.4])  # the sun's direction: down and towards the camera (its shadow in view)
HALF = 0.6  # the plane's half size (plane_mesh(1.2)), at y = 1
UPSIDE_DOWN = (1.0, 0.0, 0.0, 0.0)  # half a turn about x: the plane faces -Y, away from the lights


def plane_scene(gpu, light: str, facing_light: bool, material: str = "opaque", shadow: bool = True) -> World:
    """The ground (top at y = 0), a 1.2-unit plane at y = 1 facing up (towards the light) or down,
    lit from above by a sun, a spot light or a point light casting hard shadows."""
    world = World()
    cube, plane = gpu.meshes.add(cube_mesh()), gpu.meshes.add(plane_mesh(2.0 * HALF))
    world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(40.0, 1.0, 40.0)), Mesh(handle=cube))
    made = {
        "opaque": Material("leaf", "lambert", (0.8, 0.5, 0.3, 1.0)),
        "cutout": Material("leaf", "lambert", (0.8, 0.5, 0.3, 1.0), alpha_mode="mask"),  # the cutout pipelines
        "double-sided": Material("leaf", "lambert", (0.8, 0.5, 0.3, 1.0), double_sided=True),
    }
    leaf = materials(world).add(made["opaque" if material == "beside double-sided" else material])
    if material == "beside double-sided":  # a double-sided mesh elsewhere turns culling off for all
        other = materials(world).add(made["double-sided"])
        world.spawn(Transform(position=(-6.0, 0.5, -6.0), scale=(0.2, 0.2, 0.2)), Mesh(handle=plane, material=other))
    rotation = (0.0, 0.0, 0.0, 1.0) if facing_light else UPSIDE_DOWN
    world.spawn(Transform(position=(0.0, 1.0, 0.0), rotation=rotation), Mesh(handle=plane, material=leaf))
    cast = [Shadow(filter=SHADOW_HARD, resolution=512)] if shadow else []
    if light == "sun":
        world.spawn(Transform(rotation=look_rotation(tuple(SUN))), DirectionalLight(illuminance=0.8), *cast)
    elif light == "spot":
        world.spawn(
            Transform(position=tuple(LIGHT), rotation=look_rotation((0.0, -1.0, 0.01))),
            SpotLight(intensity=12.0, radius=20.0, inner_angle=0.9, outer_angle=1.0),
            *cast,
        )
    else:
        world.spawn(Transform(position=tuple(LIGHT)), PointLight(intensity=12.0, radius=20.0), *cast)
    add_camera(world, (0.0, 3.2, 3.6), (0.0, 0.3, 0.0))
    return world


def under_the_plane(world: World, light: str) -> np.ndarray:
    """Pixels whose ground point the plane hides from the light (a ray cast, the plane shrunk a
    little), where the camera's ray does not pass the plane first."""
    d, eye = pixel_rays(world, W, H)
    t = -eye[1] / d[..., 1]
    hit = eye + d * t[..., None]
    to_light = -SUN / np.linalg.norm(SUN) if light == "sun" else LIGHT - hit
    at = hit + to_light * (1.0 / to_light[..., 1:2])  # where the way to the light crosses y = 1
    shadowed = (np.abs(at[..., 0]) < HALF - 0.05) & (np.abs(at[..., 2]) < HALF - 0.05)
    seen_through = eye + d * ((1.0 - eye[1]) / d[..., 1])[..., None]
    in_front = (np.abs(seen_through[..., 0]) < HALF + 0.05) & (np.abs(seen_through[..., 2]) < HALF + 0.05)
    return shadowed & ~in_front & (t > 0)


CASES = [
    ("sun", "opaque"),
    ("spot", "opaque"),
    ("point", "opaque"),
    ("sun", "cutout"),
    ("spot", "cutout"),
    ("point", "cutout"),
    ("sun", "double-sided"),
    ("spot", "double-sided"),
    ("point", "double-sided"),
    ("sun", "beside double-sided"),
    ("point", "beside double-sided"),
]


@pytest.mark.parametrize(("light", "material"), CASES)
def test_single_sided_casters_cast_alike_under_every_light(light, material):
    """A plane facing the light casts its shadow; facing away, it casts one only when its
    material is double-sided: the same for sun, spot and point lights, for opaque and
    alpha-masked (cutout pipelines) materials, and for a single-sided plane in a scene with a
    double-sided material (whose shadow pipelines cull nothing)."""
    with headless_gpu(W, H) as gpu:
        world = plane_scene(gpu, light, True, material)
        towards = render_world(gpu, world)
        away = render_world(gpu, plane_scene(gpu, light, False, material))
        plain = render_world(gpu, plane_scene(gpu, light, True, material, shadow=False))
    region = under_the_plane(world, light)
    assert region.sum() > 100
    lit = plain[region].mean()
    assert towards[region].mean() < 0.5 * lit, (towards[region].mean(), lit)
    if material == "double-sided":
        assert away[region].mean() < 0.5 * lit, (away[region].mean(), lit)
    else:
        assert np.abs(away[region] - plain[region]).max() <= 1


@pytest.mark.parametrize(
    "settings",
    [dict(mode="per_entity"), dict(mode="indirect"), dict(recorder="python"), dict(light_culling="deferred")],
)
def test_every_path_draws_the_point_lights_casters_from_the_lights_side(settings):
    """The point light's maps hold the same sides in every path as in the default one (instanced,
    the views recorded in one native call): per_entity, indirect (the views culled on the GPU),
    the Python recorder, and the deferred lighting."""
    with headless_gpu(W, H) as gpu:
        images = {}
        for facing in (True, False):
            world = plane_scene(gpu, "point", facing)
            images[facing] = (render_world(gpu, world), render_world(gpu, world, **settings))
        plain = render_world(gpu, plane_scene(gpu, "point", True, shadow=False), **settings)
    region = under_the_plane(world, "point")
    for reference, image in images.values():
        assert np.abs(image - reference).max() <= 2
    assert images[True][1][region].mean() < 0.5 * plain[region].mean()
    assert np.abs(images[False][1][region] - plain[region]).max() <= 1


FOOT_LIGHT = np.array([-1.6, 2.2, 0.9])  # a point light above, beside and in front of the cube


@pytest.mark.parametrize("filter_", [SHADOW_HARD, SHADOW_PCF])
def test_a_cubes_point_light_shadow_touches_its_foot(filter_):
    """A unit cube on the ground, its point-light shadow seen from close by: the ground within
    0.1 units of the cube's foot that a ray cast says is shadowed is dark in the image. A map of
    the cube's far sides left a lit saw-tooth line along the foot (17% of those pixels lit with
    hard shadows, 29% with PCF)."""
    with headless_gpu(160, 100) as gpu:
        images = []
        for shadow in (True, False):
            world = World()
            cube = gpu.meshes.add(cube_mesh())
            world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(40.0, 1.0, 40.0)), Mesh(handle=cube))
            world.spawn(Transform(position=(0.0, 0.5, 0.0)), Mesh(handle=cube, material=1))
            cast = [Shadow(filter=filter_, resolution=512)] if shadow else []
            world.spawn(Transform(position=tuple(FOOT_LIGHT)), PointLight(intensity=12.0, radius=20.0), *cast)
            add_camera(world, (1.5, 1.2, -0.2), (0.5, 0.0, -0.3))
            images.append(render_world(gpu, world).mean(axis=-1))
    image, plain = images
    d, eye = pixel_rays(world, 160, 100)
    t = -eye[1] / d[..., 1]
    hit = eye + d * t[..., None]
    # the way from the ground point to the light crosses the cube shrunk by 0.03 at its sides
    # (its shadow's side edges, where filtering blends, are left out); y from below the ground
    shadowed = crosses(hit, FOOT_LIGHT - hit, np.array([-0.47, -1.0, -0.47]), np.array([0.47, 1.0, 0.47]))
    hidden = crosses(np.broadcast_to(eye, hit.shape), hit - eye, np.array([-0.5, 0.0, -0.5]), np.array([0.5, 1.0, 0.5]))
    gap = np.maximum(np.abs(hit[..., 0]), np.abs(hit[..., 2])) - 0.5  # from the foot, outside it
    foot = shadowed & ~hidden & (gap > 0) & (gap < 0.1) & (t > 0)
    assert foot.sum() > 200
    lit = foot & (image > 0.5 * plain)
    assert lit.sum() / foot.sum() < 0.01, lit.sum() / foot.sum()


def crosses(a: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether the segments a -> a + d cross the box [lo, hi] (slab test)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (lo - a) / d, (hi - a) / d
    enter = np.nanmax(np.minimum(t0, t1), axis=-1)
    leave = np.nanmin(np.maximum(t0, t1), axis=-1)
    return (enter <= leave) & (leave > 1e-6) & (enter < 1 - 1e-6)
