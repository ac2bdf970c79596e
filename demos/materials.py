"""The shading models side by side: a grid of spheres, one row per model (top to bottom: unlit,
Lambert, Oren-Nayar, Phong, Blinn-Phong, Cook-Torrance), roughness or shininess rising along each
row (left to right: rougher, or a smaller highlight exponent), under one directional light and
two point lights, above a floor. The Cook-Torrance row goes from smooth metal to rough dielectric."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ecs_engine import World
from ecs_engine.components import DirectionalLight, Mesh, PointLight, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import SHADING_MODELS, Material, MeshData, materials, plane_mesh, sphere_mesh

from .scene_kit import add_camera

COLUMNS = 6
SPACING = 1.25
COLORS = {
    "unlit": (0.85, 0.55, 0.25),
    "lambert": (0.80, 0.80, 0.80),
    "oren_nayar": (0.75, 0.60, 0.45),
    "phong": (0.25, 0.45, 0.85),
    "blinn_phong": (0.85, 0.30, 0.25),
    "cook_torrance": (0.95, 0.75, 0.35),
}


def row_material(model: str, t: float) -> Material:
    """The material of `model` at position t in [0, 1] along its row."""
    color = (*COLORS[model], 1.0)
    shininess = float(np.exp(np.log(256.0) * (1 - t) + np.log(4.0) * t))  # 256 down to 4
    if model == "cook_torrance":
        return Material(f"{model} {t:.1f}", model, color, metallic=1.0 - t, roughness=0.08 + 0.9 * t)
    if model in ("phong", "blinn_phong"):
        return Material(f"{model} {t:.1f}", model, color, shininess=shininess, specular=0.6)
    return Material(f"{model} {t:.1f}", model, color, roughness=t)


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    sphere = add_mesh(sphere_mesh(48, 24))
    floor = add_mesh(plane_mesh(size=1.0, subdivisions=8))
    library = materials(world)
    rows = list(SHADING_MODELS)
    for r, model in enumerate(rows):
        y = (len(rows) - 1 - r - (len(rows) - 1) / 2) * SPACING
        for c in range(COLUMNS):
            t = c / (COLUMNS - 1)
            x = (c - (COLUMNS - 1) / 2) * SPACING
            handle = library.add(row_material(model, t))
            world.spawn(Transform(position=(x, y, 0.0)), Mesh(handle=sphere, material=handle))
    ground = library.add(Material("floor", "lambert", (0.35, 0.35, 0.38, 1.0)))
    world.spawn(Transform(position=(0.0, -4.0, 0.0), scale=(14.0, 1.0, 8.0)), Mesh(handle=floor, material=ground))
    world.spawn(Transform(rotation=look_rotation((-0.4, -0.7, -0.6))), DirectionalLight(illuminance=0.45))
    world.spawn(Transform(position=(-5.0, 3.0, 4.0)), PointLight(color=(1.0, 0.85, 0.7), intensity=20.0, radius=0.0))
    world.spawn(Transform(position=(5.0, -1.0, 4.0)), PointLight(color=(0.6, 0.75, 1.0), intensity=14.0, radius=0.0))
    add_camera(world, eye=(0.0, 0.6, 10.0), target=(0.0, 0.0, 0.0), move_speed=4.0)
