"""The seed's complex scene: a model file (OBJ, glTF/GLB, PLY, STL), six orbiting lights.
Without a path it shows the torus knot that ships with the engine."""

from __future__ import annotations

from collections.abc import Callable

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.render.mesh_data import MeshData, normalized
from ecs_engine.render.mesh_loading import DEFAULT_MODEL, load_mesh

from .scene_kit import add_camera, add_orbiting_lights


def build(world: World, add_mesh: Callable[[MeshData], int], path: str | None = None) -> None:
    mesh = normalized(load_mesh(path or DEFAULT_MODEL), size=2.0)  # every model at a known size
    world.spawn(Transform(), Mesh(handle=add_mesh(mesh), material=4))
    add_camera(world, eye=(0.0, 1.2, 3.4), target=(0.0, 0.0, 0.0))
    add_orbiting_lights(world, radius=1.8, height=0.9, intensity=1.2)
