"""The seed's complex scene: a model file (OBJ, glTF/GLB, PLY, STL) with its own materials and
textures, six orbiting lights. Without a path it shows the torus knot that ships with the engine;
parts the file gives no material are drawn gold."""

from __future__ import annotations

from collections.abc import Callable

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.render import DEFAULT_MODEL, MeshData, load_model, materials, normalized_together

from .scene_kit import add_camera, add_orbiting_lights

GOLD = 4  # the default palette's gold


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    parts = load_model(path or DEFAULT_MODEL, materials(world))
    meshes = normalized_together([p.mesh for p in parts], size=2.0)  # every model at a known size
    for part, mesh in zip(parts, meshes):
        world.spawn(Transform(), Mesh(handle=add_mesh(mesh), material=GOLD if part.material is None else part.material))
    add_camera(world, eye=(0.0, 1.2, 3.4), target=(0.0, 0.0, 0.0))
    add_orbiting_lights(world, radius=1.8, height=0.9, intensity=1.2)
