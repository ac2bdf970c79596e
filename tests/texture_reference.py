"""What texture filtering should draw, in NumPy, and the two scenes that show it
(tests/test_texture_filtering.py compares them with the GPU): a 16 x 16 texture magnified six
times onto a plane filling the view, which bilinear filtering in linear light draws exactly; and a
striped floor seen at a grazing angle, whose far stripes only anisotropic filtering keeps apart.

Run as a script, it reports what a driver does with them, anisotropy off, at each level the
device offers, and by default (one JSON line each, PNGs of the magnified texture beside the
reference and their difference in OUT_DIR):

    python3 tests/texture_reference.py OUT_DIR [--validate]

Lavapipe (Mesa 22.3, LLVM 15, on the development machine) with anisotropy on (any level from 2)
strays from bilinear filtering where a texture is magnified, by up to 47 levels on 7,783 of the
9,216 pixels of the random texture here; with it off it is exact within 1.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine.render.assets.textures import linear_to_srgb, srgb_to_linear

MAGNIFIED = 96  # the magnified scene's square image, in pixels (16 texels: 6 pixels a texel)
FACING_Z = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # a plane's +Y normal -> +Z
FLOOR = (96, 64)  # the grazing scene's image


def random_texture(side: int = 16, seed: int = 3) -> np.ndarray:
    """(side, side, 4) uint8: random opaque colours, every texel unlike its neighbours."""
    px = np.random.default_rng(seed).integers(0, 256, (side, side, 4)).astype(np.uint8)
    px[..., 3] = 255
    return px


def bilinear_srgb8(pixels: np.ndarray, width: int, height: int, shift: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """(height, width, 3): an sRGB texture stretched over the whole image, each pixel centre
    filtered bilinearly (REPEAT addressing: the edges blend with the opposite side) in linear
    light, as Vulkan's sRGB formats decode before filtering, then encoded for an sRGB target.
    `shift`: every sample moved by this many texels (u, v)."""
    lin = srgb_to_linear(pixels[..., :3] / 255.0)
    rows, cols = lin.shape[:2]
    u = (np.arange(width) + 0.5) / width * cols - 0.5 + shift[0]
    v = (np.arange(height) + 0.5) / height * rows - 0.5 + shift[1]
    j0, i0 = np.floor(u).astype(int), np.floor(v).astype(int)
    fu, fv = (u - j0)[None, :, None], (v - i0)[:, None, None]
    j1, i1 = (j0 + 1) % cols, (i0 + 1) % rows
    j0, i0 = j0 % cols, i0 % rows
    top = lin[i0][:, j0] * (1 - fu) + lin[i0][:, j1] * fu
    bottom = lin[i1][:, j0] * (1 - fu) + lin[i1][:, j1] * fu
    return np.round(linear_to_srgb(top * (1 - fv) + bottom * fv) * 255.0)


def bilinear_envelope(pixels: np.ndarray, width: int, height: int, subtexel_bits: int) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest value bilinear filtering may give per pixel on a device whose
    filter weights have `subtexel_bits` bits (VkPhysicalDeviceLimits::subTexelPrecisionBits, at
    least 4): the exact filter at every sample moved by up to one step of that precision. Where
    neighbouring texels differ a lot and the result is dark, a small step is several sRGB levels
    (the NVIDIA H200's driver: up to 7 from the exact filter; lavapipe is exact)."""
    step = 2.0**-subtexel_bits
    images = [bilinear_srgb8(pixels, width, height, (du, dv)) for du in (-step, 0.0, step) for dv in (-step, 0.0, step)]
    return np.min(images, axis=0), np.max(images, axis=0)


def magnified_world(meshes: Any, pixels: np.ndarray) -> Any:
    """An unlit 2 x 2 plane textured with `pixels`, filling a 90-degree view from 1 unit away."""
    from ecs_engine import World
    from ecs_engine.components import Camera, Mesh, Transform
    from ecs_engine.render.assets.materials import Material, materials
    from ecs_engine.render.assets.primitives import plane_mesh
    from ecs_engine.render.assets.textures import Texture

    world = World()
    registry = materials(world)
    texture = registry.textures.add(Texture("random", pixels))
    material = registry.add(Material("magnified", "unlit", base_color_texture=texture))
    world.spawn(Transform(rotation=FACING_Z), Mesh(handle=meshes.add(plane_mesh(2.0)), material=material))
    world.spawn(Transform(position=(0.0, 0.0, 1.0)), Camera(fov_y=math.radians(90.0), near=0.05))
    return world


def floor_world(meshes: Any) -> Any:
    """A 40-unit unlit floor striped along the view (256 texels, stripes 2 texels wide), seen from
    0.4 units above it, looking just below the horizon: a far pixel's footprint is tens of texels
    long and one or two wide, so trilinear filtering (its level from the long side) draws the far
    stripes grey and anisotropic filtering keeps them."""
    from ecs_engine import World
    from ecs_engine.components import Camera, Mesh, Transform
    from ecs_engine.maths.camera import look_rotation
    from ecs_engine.render.assets.materials import Material, materials
    from ecs_engine.render.assets.primitives import plane_mesh
    from ecs_engine.render.assets.textures import Texture

    side = 256
    j = np.arange(side)
    px = np.zeros((side, side, 4), np.uint8)
    px[..., 3] = 255
    px[:, (j // 2) % 2 == 0, :3] = 255
    world = World()
    registry = materials(world)
    material = registry.add(Material("floor", "unlit", base_color_texture=registry.textures.add(Texture("c", px))))
    world.spawn(
        Transform(position=(0.0, 0.0, -20.0), scale=(40.0, 1.0, 40.0)),
        Mesh(handle=meshes.add(plane_mesh(1.0)), material=material),
    )
    world.spawn(
        Transform(position=(0.0, 0.4, 0.0), rotation=look_rotation((0.0, -0.12, -1.0))),
        Camera(fov_y=math.radians(50.0), near=0.05),
    )
    return world


def far_contrast(image: np.ndarray, grey: np.ndarray) -> tuple[float, float]:
    """The floor's far band, the rows (central half of the columns) that trilinear filtering
    (`grey`: the image with anisotropy off) draws nearly flat, std under 5, and not the
    background: the mean per-row std there of `image` and of `grey`."""
    w = image.shape[1]
    middle = slice(w // 4, 3 * w // 4)
    g, a = grey[:, middle].mean(axis=-1), image[:, middle].mean(axis=-1)
    background = g[0].mean()
    rows = (g.std(axis=1) < 5.0) & (np.abs(g.mean(axis=1) - background) > 30.0)  # on the floor, flat
    if not rows.any():
        return 0.0, 0.0
    return float(a[rows].std(axis=1).mean()), float(g[rows].std(axis=1).mean())


def render(device: Any, world_of: Any, size: tuple[int, int], **settings: Any) -> np.ndarray:
    """The RGB pixels (int64) of `world_of(meshes)` drawn by a new Renderer at `size`."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.gpu.offscreen import OffscreenTarget
    from ecs_engine.render.assets.mesh_registry import MeshRegistry
    from ecs_engine.render.frame.renderer import Renderer

    target = OffscreenTarget(device, *size)
    meshes = MeshRegistry(device)
    try:
        world = world_of(meshes)
        renderer = Renderer(device, target, meshes, ambient=(1.0, 1.0, 1.0, 0.0), **settings)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            return target.pixels()[..., :3].astype(np.int64)
        finally:
            renderer.destroy()
    finally:
        meshes.destroy()
        target.destroy()


def main(argv: list[str]) -> int:
    from PIL import Image

    from ecs_engine.gpu.array_image import ANISOTROPY_CHOICES, sampler_anisotropy
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance

    out = Path(argv[0]) if argv and not argv[0].startswith("-") else Path(".")
    out.mkdir(parents=True, exist_ok=True)
    instance = Instance(validate="--validate" in argv)
    device = Device(instance)
    try:
        pixels = random_texture()
        reference = bilinear_srgb8(pixels, MAGNIFIED, MAGNIFIED)
        best = sampler_anisotropy(device)
        levels: list[int | None] = [a for a in ANISOTROPY_CHOICES if a <= best] + [None]
        grey = render(device, floor_world, FLOOR, anisotropy=1)
        for level in levels:
            image = render(device, lambda m: magnified_world(m, pixels), (MAGNIFIED, MAGNIFIED), anisotropy=level)
            diff = np.abs(image - reference).max(axis=-1)
            floor = grey if level == 1 else render(device, floor_world, FLOOR, anisotropy=level)
            far, far_trilinear = far_contrast(floor, grey)
            name = "default" if level is None else f"x{level}"
            row = np.concatenate([image, reference, np.minimum(diff * 4, 255)[..., None].repeat(3, -1)], axis=1)
            Image.fromarray(row.astype(np.uint8)).save(out / f"magnified-{name}.png")
            Image.fromarray(floor.astype(np.uint8)).save(out / f"floor-{name}.png")
            line = {
                "device": device.info.name,
                "driver": device.info.driver_info,
                "anisotropy": name,
                "sampler_max_anisotropy": sampler_anisotropy(device, level),
                "magnified_max_diff": int(diff.max()),
                "magnified_pixels_off_by_more_than_1": int((diff > 1).sum()),
                "floor_far_row_std": round(far, 2),
                "floor_far_row_std_trilinear": round(far_trilinear, 2),
            }
            print(json.dumps(line), flush=True)
    finally:
        device.destroy()
        instance.destroy()
    if instance.messages:
        print(f"{len(instance.messages)} validation messages:", *instance.messages[:5], sep="\n")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
