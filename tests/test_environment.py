"""Environment maps drawn (render/lighting/environment.py, sky_pass.py, shaders/environment.glsl): the sky
shows the cube face each pixel looks at; a mirror's reflection follows Schlick's Fresnel with its
reflectivity at normal incidence; glass bends the view through it (a sphere shows the far side of
the sky); a uniform environment lights a white Lambert surface with its own radiance; the forward
and deferred forms agree; a broken sky file is one clear error."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu
from pixel_rays import pixel_rays
from shading_reference import lobe_integral

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Environment, Mesh, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh, sphere_mesh
from ecs_engine.render.assets.textures import linear_to_srgb
from ecs_engine.render.lighting.environment_maps import cube_directions

W, H = 160, 100
FACE_COLORS = np.array([(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (0, 1, 1), (1, 0, 1)], np.float32)


def flat_faces(colors=FACE_COLORS, side: int = 16) -> np.ndarray:
    return np.broadcast_to(np.asarray(colors, np.float32)[:, None, None, :], (6, side, side, 3)).copy()


def render(gpu, world: World, **settings) -> np.ndarray:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].astype(int)
    finally:
        renderer.destroy()


def encoded(linear: np.ndarray) -> np.ndarray:
    """What the target stores for a linear colour (the clamp tone map into an sRGB image)."""
    return np.round(linear_to_srgb(np.asarray(linear, np.float64)) * 255.0)


def test_the_sky_shows_the_face_each_pixel_looks_at():
    """Six flat faces: each pixel is its ray's face's colour (Vulkan's face selection: the major
    axis), seen from a camera turned off every axis."""
    with headless_gpu(W, H) as gpu:
        world = World()
        world.resources[Environment] = Environment(flat_faces())
        add_camera(world, (0.0, 0.0, 0.0), (1.0, 0.9, -1.1))  # towards a corner: +X, +Y and -Z
        image = render(gpu, world)
        rays, _ = pixel_rays(world, W, H)
    major = np.abs(rays).argmax(axis=-1)
    face = 2 * major + (np.take_along_axis(rays, major[..., None], -1)[..., 0] < 0)
    # pixels within a texel of a face's edge mix two faces (bilinear): left out
    top2 = np.sort(np.abs(rays), axis=-1)
    clear = top2[..., 2] - top2[..., 1] > 0.1
    expected = encoded(FACE_COLORS[face])
    assert len(np.unique(face[clear])) >= 3  # several faces in view
    assert np.abs(image - expected)[clear].max() <= 1
    assert clear.mean() > 0.6


def mirror_world(gpu, reflectivity: float, model: str = "lambert") -> World:
    """A black plane (top at y = 0) seen from above at a slant, in a uniform white environment
    without the sky: what shows is the reflection alone."""
    world = World()
    cube = gpu.meshes.add(cube_mesh())
    look = materials(world).add(Material("mirror", model, (0.0, 0.0, 0.0, 1.0), reflectivity=reflectivity))
    world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(400.0, 1.0, 400.0)), Mesh(handle=cube, material=look))
    world.resources[Environment] = Environment(flat_faces(np.full((6, 3), 0.6)), sky=False, ambient=False)
    add_camera(world, (0.0, 2.0, 6.0), (0.0, 0.0, -2.0))
    return world


@pytest.mark.parametrize("reflectivity", [0.1, 0.5])
def test_a_mirror_reflects_by_schlicks_fresnel(reflectivity):
    """A plane reflecting a uniform environment of radiance 0.6 shows 0.6 * F, F = r + (1 - r)
    (1 - n.v)^5: brighter towards the horizon, `r` of it looking straight down."""
    with headless_gpu(W, H) as gpu:
        world = mirror_world(gpu, reflectivity)
        image = render(gpu, world, ambient=(0.0, 0.0, 0.0, 0.0))
        rays, _ = pixel_rays(world, W, H)
    hits = rays[..., 1] < -0.05  # the plane, not too near the horizon (it reaches 200 units)
    cos = -rays[..., 1]
    fresnel = reflectivity + (1.0 - reflectivity) * (1.0 - cos) ** 5
    expected = encoded(0.6 * fresnel)
    assert hits.mean() > 0.5
    assert np.abs(image[..., 0] - expected)[hits].max() <= 2
    grazing, steep = image[hits][:, 0].max(), image[hits][:, 0].min()
    assert grazing - steep > 10  # the Fresnel term shows across the image


def test_a_rough_mirror_shows_the_ggx_blurred_sky():
    """A plane of reflectivity 1 and roughness 1 under a sky bright overhead and dark below: each
    pixel is the GGX lobe's average of the sky around its reflected ray (the split sum's
    prefilter, integrated here over every sky texel), read from the prefiltered chain's level for
    roughness 1 (4 x 4 faces, so within a few levels of 255 of the exact integral)."""
    side = 16
    d = cube_directions(side)
    sky = (0.05 + 0.7 * np.clip(d[..., 1:2], 0.0, 1.0) ** 2 + 0.2 * np.clip(d[..., :1], 0.0, 1.0)).repeat(3, -1)
    with headless_gpu(W, H) as gpu:
        world = World()
        cube = gpu.meshes.add(cube_mesh())
        look = materials(world).add(Material("rough", "lambert", (0.0, 0.0, 0.0, 1.0), reflectivity=1.0, roughness=1.0))
        world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(400.0, 1.0, 400.0)), Mesh(handle=cube, material=look))
        world.resources[Environment] = Environment(sky.astype(np.float32), sky=False, ambient=False)
        add_camera(world, (0.0, 2.0, 6.0), (1.0, 0.0, -2.0))
        image = render(gpu, world, ambient=(0.0, 0.0, 0.0, 0.0))
        rays, _ = pixel_rays(world, W, H)
    hits = rays[..., 1] < -0.05
    reflected = rays[hits] * np.array([1.0, -1.0, 1.0])
    expected = encoded(lobe_integral(sky, reflected / np.linalg.norm(reflected, axis=-1, keepdims=True), 1.0))
    error = np.abs(image[hits] - expected)
    assert hits.mean() > 0.5
    assert error.mean() <= 2.0 and error.max() <= 6, (error.mean(), error.max())
    assert np.ptp(expected[:, 0]) > 40  # the blurred sky varies across the plane


def test_glass_shows_the_sky_behind_it_bent():
    """A glass sphere in front of a sky red where x < 0 and blue where x > 0: rays through its
    left side bend towards +x (index 1.5), so the sphere's left shows blue where the sky beside it
    is red; an opaque sphere there shows neither."""
    height = 32
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(2 * height) + 0.5) / (2 * height)
    x = np.sin(np.pi * v)[:, None] * np.sin((u - 0.5) * 2 * np.pi)[None, :]
    sky = np.where((x < 0)[..., None], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]).astype(np.float32)
    results = {}
    for refraction in (1.0, 0.0):
        with headless_gpu(W, H) as gpu:
            world = World()
            sphere = gpu.meshes.add(sphere_mesh(segments=64, rings=32, radius=1.0))
            look = materials(world).add(
                Material("glass", "lambert", (1.0, 1.0, 1.0, 1.0), roughness=0.0, refraction=refraction, ior=1.5)
            )
            world.spawn(Transform(), Mesh(handle=sphere, material=look))
            world.resources[Environment] = Environment(sky, ambient=False)
            add_camera(world, (0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
            results[refraction] = render(gpu, world, ambient=(0.0, 0.0, 0.0, 0.0))
    glass, opaque = results[1.0], results[0.0]
    row = H // 2
    columns = np.flatnonzero(np.abs(glass[row] - opaque[row]).sum(axis=-1) > 0)  # where the sphere is
    assert len(columns) > 20
    left = columns[len(columns) // 8 : len(columns) // 4]  # left of centre, short of the rim (Fresnel)
    outside = columns[0] - 3  # the sky just left of it
    assert (glass[row, outside] == [255, 0, 0]).all()
    # blue, bent to +x; the red is the Fresnel reflection (about 4% head-on, 57/255 in sRGB)
    assert (glass[row, left, 2] > 240).all() and (glass[row, left, 0] < 80).all()
    assert (opaque[row, left] < 30).all()  # black and unlit: no environment in an opaque sphere


@pytest.mark.parametrize("light_culling", ["loop", "deferred"])
def test_a_uniform_environment_lights_white_with_its_radiance(light_culling):
    """Image-based ambient: in an environment of radiance L everywhere, a white Lambert sphere
    reflects L (the harmonics of a constant are exact); without `ambient` the flat ambient
    colour lights it instead. Forward and deferred agree."""
    level = 0.35
    with headless_gpu(W, H) as gpu:
        world = World()
        sphere = gpu.meshes.add(sphere_mesh(radius=1.0))
        white = materials(world).add(Material("white", "lambert", (1.0, 1.0, 1.0, 1.0)))
        world.spawn(Transform(), Mesh(handle=sphere, material=white))
        world.resources[Environment] = Environment(flat_faces(np.full((6, 3), level)), sky=False)
        add_camera(world, (0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
        settings = dict(ambient=(1.0, 1.0, 1.0, 0.0), light_culling=light_culling)
        lit = render(gpu, world, **settings)
        world.resources[Environment] = Environment(flat_faces(np.full((6, 3), level)), sky=False, ambient=False)
        flat = render(gpu, world, **settings)
    centre = lit[H // 2 - 10 : H // 2 + 10, W // 2 - 10 : W // 2 + 10]
    assert np.abs(centre - encoded(level)).max() <= 2
    assert flat[H // 2, W // 2].max() == 0  # the flat ambient's intensity is 0 here


def test_a_world_without_an_environment_compiles_none_of_it():
    from ecs_engine.render.frame.renderer import Renderer
    from ecs_engine.render.layouts import FEATURE_ENVIRONMENT

    with headless_gpu(W, H) as gpu:
        world = World()
        cube = gpu.meshes.add(cube_mesh())
        world.spawn(Transform(), Mesh(handle=cube))
        add_camera(world, (0.0, 1.0, 4.0), (0.0, 0.0, 0.0))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            assert not renderer.material_features & FEATURE_ENVIRONMENT
            assert not renderer.environment.active
            world.resources[Environment] = Environment(flat_faces())
            renderer.render(world, readback=True)
            assert renderer.material_features & FEATURE_ENVIRONMENT and renderer.environment.active
        finally:
            renderer.destroy()


def test_a_broken_sky_file_is_one_clear_error_and_keeps_the_old_sky(tmp_path):
    from ecs_engine.render.frame.renderer import Renderer

    broken = tmp_path / "sky.hdr"
    broken.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8 +X 16\n" + b"\x01" * 10)
    with headless_gpu(W, H) as gpu:
        world = World()
        add_camera(world, (0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
        world.resources[Environment] = Environment(flat_faces())
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            before = gpu.target.pixels().copy()
            world.resources[Environment] = Environment(broken)
            with pytest.raises(UsageError, match=r"sky\.hdr"):
                renderer.render(world, readback=True)
            world.resources[Environment] = renderer.environment.source  # the one still bound
            renderer.render(world, readback=True)
            assert np.array_equal(gpu.target.pixels(), before)
        finally:
            renderer.destroy()


def test_environment_settings_are_checked():
    for bad in (dict(intensity=-1.0), dict(intensity=math.nan), dict(size=0), dict(sky="yes")):
        with pytest.raises(ValueError):
            Environment(flat_faces(), **bad)
    with pytest.raises(ValueError, match="reflectivity"):
        Material("m", reflectivity=1.5)
    with pytest.raises(ValueError, match="ior"):
        Material("m", ior=0.5)


def test_changing_the_intensity_keeps_the_image_and_scales_the_light():
    """The editor replaces the Environment to change its intensity, sky or ambient: the cube map
    is not loaded again (same source and size), and the sky's radiance follows the intensity."""
    from dataclasses import replace

    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = World()
        add_camera(world, (0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
        world.resources[Environment] = Environment(flat_faces(np.full((6, 3), 0.2)))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            image = renderer.environment.image
            dim = gpu.target.pixels()[H // 2, W // 2, :3].astype(int)
            world.resources[Environment] = replace(world.resources[Environment], intensity=2.0)
            renderer.render(world, readback=True)
            bright = gpu.target.pixels()[H // 2, W // 2, :3].astype(int)
            assert renderer.environment.image is image  # not uploaded again
            world.resources[Environment] = replace(world.resources[Environment], sky=False)
            renderer.render(world, readback=True)
            hidden = gpu.target.pixels()[H // 2, W // 2, :3].astype(int)
        finally:
            renderer.destroy()
    assert np.abs(dim - encoded(0.2)).max() <= 1 and np.abs(bright - encoded(0.4)).max() <= 1
    assert np.abs(hidden - encoded((0.02, 0.02, 0.03))).max() <= 1  # the clear colour
