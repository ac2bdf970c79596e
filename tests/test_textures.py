"""Textures: the CPU registry (conversions, files, the fallback and its one warning, mip chains)
and what the GPU draws with them (lavapipe, validation on): orientation, sRGB against linear data,
mips, per-instance textures in one instanced draw, normal, emissive and occlusion maps."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, Materials, materials
from ecs_engine.render.assets.primitives import cube_mesh, plane_mesh
from ecs_engine.render.assets.textures import (
    CLASS_SIZES,
    Texture,
    Textures,
    linear_to_srgb,
    mip_chain,
    size_class,
    srgb_to_linear,
)

W, H = 96, 96
FACING_Z = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # +Y (the plane's normal) -> +Z


def quadrants(side: int = 32) -> np.ndarray:
    """Red top-left, green top-right, blue bottom-left, white bottom-right."""
    out = np.zeros((side, side, 4), np.uint8)
    out[..., 3] = 255
    h = side // 2
    out[:h, :h, 0] = 255
    out[:h, h:, 1] = 255
    out[h:, :h, 2] = 255
    out[h:, h:, :3] = 255
    return out


# ---------------------------------------------------------------------------------------- CPU
def test_texture_takes_grey_rgb_and_float_pixels():
    grey = Texture("g", np.full((2, 3), 7, np.uint8))
    assert grey.pixels.shape == (2, 3, 4) and (grey.pixels[..., :3] == 7).all() and (grey.pixels[..., 3] == 255).all()
    ga = Texture("ga", np.dstack([np.full((2, 2), 9, np.uint8), np.full((2, 2), 100, np.uint8)]))
    assert (ga.pixels[0, 0] == (9, 9, 9, 100)).all()
    f = Texture("f", np.full((1, 1, 3), 0.5))
    assert (f.pixels[0, 0] == (128, 128, 128, 255)).all()
    assert f.size == (1, 1) and not f.pixels.flags.writeable
    for bad in (np.zeros((2, 2, 5), np.uint8), np.zeros((0, 2, 3), np.uint8), np.full((1, 1, 3), np.nan)):
        with pytest.raises(ValueError, match="texture"):
            Texture("bad", bad)


def test_missing_or_broken_file_gives_the_fallback_and_one_warning(tmp_path, caplog):
    textures = Textures()
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"\x89PNG\r\n\x1a\n not really")
    with caplog.at_level(logging.WARNING, logger="ecs_engine"):
        a = textures.load(tmp_path / "missing.png")
        b = textures.load(broken)
        again = textures.load(tmp_path / "missing.png")  # asked twice: still one warning
    assert a == b == again == textures.fallback
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 2
    assert "missing.png" in lines[0] and "no such file" in lines[0] and "fallback" in lines[0]
    assert "broken.png" in lines[1]
    checker = textures[textures.fallback].pixels
    assert {tuple(p) for p in checker.reshape(-1, 4)} == {(255, 0, 255, 255), (0, 0, 0, 255)}


def test_load_reads_a_file_once_per_colour_space(tmp_path):
    from PIL import Image

    path = tmp_path / "q.png"
    Image.fromarray(quadrants(8)).save(path)
    textures = Textures()
    colour = textures.load(path)
    assert textures.load(path) == colour
    data = textures.load(path, color=False)
    assert data != colour and not textures[data].color
    assert (textures[colour].pixels == quadrants(8)).all()


def test_size_classes():
    assert CLASS_SIZES[0] == 16 and CLASS_SIZES[-1] == 4096
    assert CLASS_SIZES[size_class(1, 1)] == 16
    assert CLASS_SIZES[size_class(64, 64)] == 64
    assert CLASS_SIZES[size_class(100, 20)] == 128  # nearest power of two in log scale
    assert CLASS_SIZES[size_class(1000, 1000)] == 1024
    assert CLASS_SIZES[size_class(20000, 20)] == 4096


def test_mip_chain_averages_colour_in_linear_light_and_data_as_stored():
    checker = np.zeros((4, 4, 4), np.uint8)
    checker[..., 3] = 255
    checker[::2, ::2, :3] = 255
    checker[1::2, 1::2, :3] = 255
    colour = mip_chain(checker, color=True)
    data = mip_chain(checker, color=False)
    assert [level.shape[0] for level in colour] == [4, 2, 1]
    # half the texels white: linear 0.5, which sRGB stores as 188 (not 128, the encoded mean)
    assert (colour[-1][0, 0, :3] == 188).all()
    assert (data[-1][0, 0, :3] == 128).all()
    assert srgb_to_linear(linear_to_srgb(np.array([0.25]))) == pytest.approx(0.25)


def test_mip_chain_keeps_transparent_texels_colour_out():
    px = np.zeros((2, 2, 4), np.uint8)
    px[0, 0] = (255, 0, 0, 255)  # one opaque red texel, three transparent green ones
    px[0, 1] = px[1, 0] = px[1, 1] = (0, 255, 0, 0)
    top = mip_chain(px, color=True)[-1][0, 0]
    assert tuple(top[:3]) == (255, 0, 0) and top[3] == 64


def test_materials_check_texture_handles():
    registry = Materials()
    with pytest.raises(ValueError, match="not a texture of this registry"):
        registry.add(Material("m", base_color_texture=0))
    t = registry.textures.add(Texture("t", quadrants(16)))
    h = registry.add(Material("m", base_color_texture=t))
    with pytest.raises(ValueError, match="not a texture"):
        registry.update(h, normal_texture=5)
    with pytest.raises(ValueError, match="texture handle"):
        Material("m", base_color_texture=-1)
    with pytest.raises(ValueError, match="texture handle"):
        Material("m", normal_texture=True)


# ---------------------------------------------------------------------------------------- GPU
def render(gpu, world: World, ambient=(1.0, 1.0, 1.0, 0.0)) -> np.ndarray:
    # anisotropy off: these compare with (tri)linear filtering, which every driver draws alike;
    # lavapipe's anisotropic filter strays from it (test_texture_filtering.py)
    return render_world(gpu, world, ambient=ambient, anisotropy=1)


def facing_plane(gpu, world: World, material: int, size: float = 2.0, position=(0.0, 0.0, 0.0)) -> None:
    mesh = gpu.meshes.add(plane_mesh(size))
    world.spawn(Transform(position=position, rotation=FACING_Z), Mesh(handle=mesh, material=material))


def camera(world: World, z: float = 2.0, fov: float = 60.0) -> None:
    world.spawn(Transform(position=(0.0, 0.0, z)), Camera(fov_y=math.radians(fov), near=0.05))


def test_a_texture_is_drawn_upright_with_its_colours():
    """Texel (0, 0) is the image's top-left and shows at the plane's top-left, as in glTF."""
    with headless_gpu(W, H) as gpu:
        world = World()
        registry = materials(world)
        tex = registry.textures.add(Texture("q", quadrants(32)))
        facing_plane(gpu, world, registry.add(Material("q", "unlit", base_color_texture=tex)), size=2.0)
        camera(world, z=1.0, fov=90.0)  # the 2 x 2 plane fills the view exactly
        img = render(gpu, world)
    q = W // 4
    expected = {(q, q): (255, 0, 0), (q, 3 * q): (0, 255, 0), (3 * q, q): (0, 0, 255), (3 * q, 3 * q): (255, 255, 255)}
    for (y, x), want in expected.items():
        assert np.abs(img[y, x] - want).max() <= 2, (y, x, img[y, x])


def test_colour_textures_are_decoded_from_srgb_and_data_is_not():
    """The same texel (188) as colour comes back as 188 (decoded, then encoded on write); as data
    it counts as 188/255 linear, which the sRGB target stores as about 224."""
    px = np.full((16, 16, 4), 188, np.uint8)
    px[..., 3] = 255
    with headless_gpu(W, H) as gpu:
        world = World()
        registry = materials(world)
        colour = registry.textures.add(Texture("c", px, color=True))
        data = registry.textures.add(Texture("d", px, color=False))
        facing_plane(gpu, world, registry.add(Material("c", "unlit", base_color_texture=colour)), 1.0, (-0.6, 0, 0))
        facing_plane(gpu, world, registry.add(Material("d", "unlit", base_color_texture=data)), 1.0, (0.6, 0, 0))
        camera(world, z=2.0)
        img = render(gpu, world)
    left, right = img[H // 2, int(W * 0.3)], img[H // 2, int(W * 0.7)]
    assert np.abs(left - 188).max() <= 1
    want = round(float(linear_to_srgb(np.array(188 / 255))) * 255)
    assert np.abs(right - want).max() <= 1 and want >= 220


def test_far_away_checker_averages_through_the_mips():
    """A 1-texel black-and-white checker seen small: with the mip chain it averages to linear
    grey (sRGB 188); level 0 alone would alias into black and white noise."""
    side = 256
    cells = (np.indices((side, side)).sum(axis=0) % 2 * 255).astype(np.uint8)
    with headless_gpu(W, H) as gpu:
        world = World()
        registry = materials(world)
        tex = registry.textures.add(Texture("checker", cells))
        facing_plane(gpu, world, registry.add(Material("c", "unlit", base_color_texture=tex)), size=1.0)
        camera(world, z=1.2)
        img = render(gpu, world)
    centre = img[H // 2 - 8 : H // 2 + 8, W // 2 - 8 : W // 2 + 8].reshape(-1, 3)
    assert np.abs(centre - 188).max() <= 6, (centre.min(), centre.max())


def test_instances_of_one_mesh_each_sample_their_own_texture():
    """One instanced draw, materials differing per instance, textures of different size classes."""
    colours = [(255, 0, 0), (0, 255, 0), (0, 0, 255), (255, 255, 0)]
    sizes = [16, 64, 16, 256]
    with headless_gpu(W, H) as gpu:
        world = World()
        registry = materials(world)
        mesh = gpu.meshes.add(cube_mesh())
        for i, (colour, side) in enumerate(zip(colours, sizes)):
            px = np.zeros((side, side, 4), np.uint8)
            px[...] = (*colour, 255)
            tex = registry.textures.add(Texture(f"t{i}", px))
            handle = registry.add(Material(f"m{i}", "unlit", base_color_texture=tex))
            world.spawn(
                Transform(position=(-1.5 + i, 0.0, 0.0), scale=(0.6, 0.6, 0.6)), Mesh(handle=mesh, material=handle)
            )
        camera(world, z=4.0)
        img = render(gpu, world)
    row = img[H // 2]
    for i, colour in enumerate(colours):
        x = round(W / 2 + (-1.5 + i) * (W / 2) / (4.0 * math.tan(math.radians(30))))
        assert np.abs(row[x] - colour).max() <= 2, (i, row[x])


def lit_plane_world(gpu, material: Material, pixels: dict[str, np.ndarray]) -> World:
    world = World()
    registry = materials(world)
    handles = {}
    for field, px in pixels.items():
        handles[field] = registry.textures.add(Texture(field, px, color=field in ("base_color", "emissive")))
    m = registry.add(Material(**{**material.__dict__, **{f"{k}_texture": v for k, v in handles.items()}}))
    facing_plane(gpu, world, m, size=2.0)
    camera(world, z=1.0, fov=90.0)
    return world


def flat(value, side: int = 16) -> np.ndarray:
    px = np.zeros((side, side, 4), np.uint8)
    px[...] = value
    return px


def test_normal_map_tilts_the_shading_normal_as_the_tangent_frame_says():
    """Lambert under a light from the right (+X, the plane's +u): a flat normal map (128, 128, 255)
    changes nothing; one leaning towards +u brightens by n'.l / n.l, computed here."""
    light_dir = np.array([-0.6, 0.0, -0.8])  # travelling left (-X) and into the plane: from the right front
    base = Material("n", "lambert", base_color=(0.5, 0.5, 0.5, 1.0))
    lean = np.array([0.5, 0.0, math.sqrt(0.75)])  # tangent space, towards +u
    encoded = np.round((lean * 0.5 + 0.5) * 255).astype(np.uint8)
    results = {}
    with headless_gpu(W, H) as gpu:
        for name, px in (("none", None), ("flat", flat((128, 128, 255, 255))), ("lean", flat((*encoded, 255)))):
            world = lit_plane_world(gpu, base, {} if px is None else {"normal": px})
            world.spawn(Transform(rotation=look_rotation(light_dir)), DirectionalLight(illuminance=1.0))
            results[name] = render(gpu, world)[H // 2, W // 2]
    assert np.abs(results["flat"] - results["none"]).max() <= 1
    decoded = encoded / 255 * 2 - 1
    n_lean = decoded / np.linalg.norm(decoded)  # tangent x = +X, bitangent y = +Y, normal z = +Z here
    to_light = -light_dir
    expected = [0.5 * max(n @ to_light, 0.0) for n in (np.array([0.0, 0.0, 1.0]), n_lean)]
    want = np.round(linear_to_srgb(np.array(expected)) * 255)
    assert abs(results["none"][0] - want[0]) <= 1
    assert abs(results["lean"][0] - want[1]) <= 1 and want[1] > want[0] + 10


def test_emissive_occlusion_and_metallic_roughness_maps():
    with headless_gpu(W, H) as gpu:
        # emissive texture times the emissive factor, on a black unlit surface
        world = lit_plane_world(
            gpu,
            Material("e", "unlit", base_color=(0, 0, 0, 1), emissive=(1.0, 0.5, 1.0)),
            {"emissive": flat((255, 255, 0, 255))},
        )
        got = render(gpu, world)[H // 2, W // 2]
        assert np.abs(got - (255, 188, 0)).max() <= 1
        # occlusion (R = 0.25) with strength 1 scales the ambient light: no other light here
        shades = []
        for px in (None, flat((64, 255, 255, 255))):
            world = lit_plane_world(gpu, Material("o", "lambert"), {} if px is None else {"occlusion": px})
            shades.append(render(gpu, world, ambient=(1.0, 1.0, 1.0, 0.5))[H // 2, W // 2][0])
        want = np.round(linear_to_srgb(np.array([0.5, 0.5 * 64 / 255])) * 255)
        assert abs(shades[0] - want[0]) <= 1 and abs(shades[1] - want[1]) <= 1
        # metallic-roughness: B = 1 makes a metallic 1.0 surface fully metallic; B = 0 a dielectric
        looks = []
        for b in (255, 0):
            world = lit_plane_world(
                gpu,
                Material("mr", "cook_torrance", base_color=(0.2, 0.9, 0.2, 1.0), metallic=1.0, roughness=1.0),
                {"metallic_roughness": flat((0, 255, b, 255))},
            )
            world.spawn(Transform(rotation=look_rotation((0.0, 0.0, -1.0))), DirectionalLight(illuminance=1.0))
            looks.append(render(gpu, world)[H // 2, W // 2])
        metal, dielectric = looks
        assert metal[1] > metal[0] + 40  # a green metal reflects green
        assert abs(int(metal[0]) - int(dielectric[0])) > 5  # the map's B changed the look


def test_textures_added_after_the_first_frame_are_uploaded():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = World()
        registry = materials(world)
        h = registry.add(Material("late", "unlit"))
        facing_plane(gpu, world, h, size=2.0)
        camera(world, z=1.0, fov=90.0)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            assert (gpu.target.pixels()[H // 2, W // 2, :3] == 255).all()
            tex = registry.textures.add(Texture("blue", flat((0, 0, 255, 255))))
            registry.update(h, base_color_texture=tex)
            renderer.render(world, readback=True)
            assert tuple(gpu.target.pixels()[H // 2, W // 2, :3]) == (0, 0, 255)
        finally:
            renderer.destroy()
