"""Environment maps (issue 15): spheres in front of a sky, each showing the environment another
way: a mirror (reflectivity 1), glass (refraction, index 1.5), rough and polished metal and a
plastic lit by the environment alone (image-based ambient: harmonics for the diffuse, the mip
chain for the specular), and a plain Lambert sphere; a sun lights them and casts their shadows
on a ground disc. The sky is `path` (an equirectangular .hdr or 8-bit image, the demo's second
argument) or, without one, `default_sky()`: a gradient with a sun and a checkered ground, made
here so the demo needs no file."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import DirectionalLight, Environment, Mesh, Shadow, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, MeshData, cube_mesh, materials, sphere_mesh

from .scene_kit import add_camera

SUN = np.array([0.4, 0.75, -0.55])  # towards the sun


def default_sky(height: int = 256) -> np.ndarray:
    """(height, 2 * height, 3) linear radiance, equirectangular (environment_maps.load_cube's
    mapping: column 0 at longitude -pi, +Y up): a blue gradient above the horizon, a small bright
    sun towards SUN, and below the horizon a grey-brown checkered ground."""
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(2 * height) + 0.5) / (2 * height)
    theta, phi = np.meshgrid(v * np.pi, (u - 0.5) * 2 * np.pi, indexing="ij")
    d = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)
    up = np.clip(d[..., 1], 0.0, 1.0)[..., None]
    sky = (1.0 - up) * np.array([0.75, 0.85, 1.0]) + up * np.array([0.15, 0.35, 0.8])
    sun = SUN / np.linalg.norm(SUN)
    glow = np.clip(d @ sun, 0.0, 1.0)
    sky = sky + (glow**2000)[..., None] * 60.0 + (glow**16)[..., None] * np.array([0.5, 0.4, 0.2])
    # the ground: where a downward ray meets the plane y = -1, 2-unit squares
    t = np.where(d[..., 1] < -1e-3, -1.0 / np.minimum(d[..., 1], -1e-3), 0.0)
    cells = (np.floor(d[..., 0] * t / 2.0) + np.floor(d[..., 2] * t / 2.0)).astype(int) % 2
    ground = np.where(cells[..., None] == 0, [0.35, 0.3, 0.25], [0.18, 0.16, 0.14])
    fade = np.clip(-d[..., 1] * 8.0, 0.0, 1.0)[..., None]  # the ground blends into the horizon
    below = d[..., 1] < 0
    out = np.where(below[..., None], fade * ground + (1.0 - fade) * np.array([0.6, 0.62, 0.65]), sky)
    return out.astype(np.float32)


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    sphere = add_mesh(sphere_mesh(segments=64, rings=32))
    cube = add_mesh(cube_mesh())
    library = materials(world)
    looks = [
        Material("mirror", "cook_torrance", (0.95, 0.95, 0.95, 1.0), metallic=1.0, roughness=0.02, reflectivity=1.0),
        Material("glass", "cook_torrance", (1.0, 1.0, 1.0, 1.0), roughness=0.0, refraction=0.95, ior=1.5),
        Material("brushed gold", "cook_torrance", (1.0, 0.78, 0.34, 1.0), metallic=1.0, roughness=0.35),
        Material("red plastic", "cook_torrance", (0.8, 0.08, 0.05, 1.0), roughness=0.3),
        Material("chalk", "lambert", (0.85, 0.85, 0.85, 1.0)),
    ]
    for i, look in enumerate(looks):
        world.spawn(Transform(position=(1.25 * (i - 2), 0.5, 0.0)), Mesh(handle=sphere, material=library.add(look)))
    floor = library.add(Material("floor", "cook_torrance", (0.5, 0.5, 0.52, 1.0), roughness=0.8))
    world.spawn(Transform(position=(0.0, -0.05, 0.0), scale=(8.0, 0.1, 3.0)), Mesh(handle=cube, material=floor))
    world.spawn(
        Transform(rotation=look_rotation(-SUN)), DirectionalLight(color=(1.0, 0.95, 0.85), illuminance=1.2), Shadow()
    )
    world.resources[Environment] = Environment(path if path is not None else default_sky())
    add_camera(world, (0.0, 1.6, 4.6), (0.0, 0.45, 0.0))
