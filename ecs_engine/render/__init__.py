"""From the world to the GPU, by concern: graph/ (the frame graph), config/ (one render
configuration and its rules), extract/ (the World turned into the frame's snapshot), culling/,
post/ (post effects as plugins), and
- frame/: One frame from FrameData to a submitted command buffer: the Renderer, what each frame
  slot owns, frame replay, the frame's chunk jobs, the camera's matrices as the frame uses them.
- draw/: The render paths that draw the mesh rows: the RenderPath interface (path.py), the CPU-
  recorded paths (chunk_paths.py), the indirect path, the instance rows and their recording.
- passes/: The frame's passes besides the mesh rows: sky, set-aside rows, weighted transparency,
  light billboards, the tone map and the output's post-effect stage.
- lighting/: Lights and environment: clustered light lists, the light rows, deferred lighting,
  the environment map (its CPU cube maths, GGX prefilter and Radiance .hdr reader).
- shadows/: Shadow maps: the views per light, their descriptor sets, the maps' pass and the
  indirect mode's GPU-culled views.
- raytracing/: Ray-traced shadows: the top-level instances, the trace, its mask and denoise.
- assets/: What scenes are made of: meshes (data, loading, levels of detail, the GPU registry),
  materials, textures (and their GPU pages), primitives and the scene files' asset codecs.
- ui/: Dear ImGui drawn by the engine: its pass, its texture uploads and engine images shown in
  it.
layouts.py holds the layouts the CPU and the shaders share; picking.py the entity under a pixel.

Games import what scenes are made of from here (`from ecs_engine.render import Material, Meshes,
cube_mesh`): each name is loaded on first use, so importing one module of a sub-package loads no
other (numba's kernels, trimesh). Code of the engine imports the module that defines a name.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .assets.materials import SHADING_MODELS, Material, Materials, materials
    from .assets.mesh_data import MeshData, normalized, normalized_together
    from .assets.mesh_loading import DEFAULT_MODEL, load_mesh
    from .assets.meshes import Meshes
    from .assets.model_loading import load_model
    from .assets.primitives import cone_mesh, cube_mesh, cylinder_mesh, plane_mesh, sphere_mesh, torus_mesh
    from .assets.textures import Texture, Textures

_PUBLIC = {
    "SHADING_MODELS": "assets.materials",
    "Material": "assets.materials",
    "Materials": "assets.materials",
    "materials": "assets.materials",
    "Meshes": "assets.meshes",
    "MeshData": "assets.mesh_data",
    "normalized": "assets.mesh_data",
    "normalized_together": "assets.mesh_data",
    "cube_mesh": "assets.primitives",
    "sphere_mesh": "assets.primitives",
    "plane_mesh": "assets.primitives",
    "cylinder_mesh": "assets.primitives",
    "cone_mesh": "assets.primitives",
    "torus_mesh": "assets.primitives",
    "Texture": "assets.textures",
    "Textures": "assets.textures",
    "DEFAULT_MODEL": "assets.mesh_loading",
    "load_mesh": "assets.mesh_loading",
    "load_model": "assets.model_loading",
}


def __getattr__(name: str) -> Any:
    if name in _PUBLIC:
        return getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "DEFAULT_MODEL",
    "SHADING_MODELS",
    "Material",
    "Materials",
    "MeshData",
    "Meshes",
    "Texture",
    "Textures",
    "cone_mesh",
    "cube_mesh",
    "cylinder_mesh",
    "load_mesh",
    "load_model",
    "materials",
    "normalized",
    "normalized_together",
    "plane_mesh",
    "sphere_mesh",
    "torus_mesh",
]
