"""`Meshes`: the meshes that entities' `Mesh.handle` names, as a world resource.

An App puts one in its world (`world.resources[Meshes]`) before its startup systems run:

    handle = world.resources[Meshes].add(cube_mesh())       # a primitive (render/assets/primitives.py)
    ship = world.resources[Meshes].load("ship.glb")        # a model file, its parts as one mesh
    world.spawn(Transform(), Mesh(handle=handle))

Over a renderer's MeshRegistry it uploads each mesh once (an equal mesh gives the same handle);
in a run without a GPU (MinimalPlugins) it keeps the MeshData on the CPU (`MeshList`), so a
simulation's handles, bounds for picking and saved scenes work the same. Saved scenes refer to
a mesh by how it was made (a primitive's arguments, a file's path) where they can
(render/assets/scene_assets.py): `world.save(path)` in an App keeps them with no extra argument.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from .mesh_data import MeshData


class MeshList:
    """A mesh registry without a GPU: MeshData by handle, an equal mesh reusing its handle."""

    def __init__(self, meshes: list[MeshData] | None = None) -> None:
        self._meshes: list[MeshData] = list(meshes or ())

    def add(self, mesh: MeshData) -> int:
        for handle, have in enumerate(self._meshes):
            if have is mesh or _same(have, mesh):
                return handle
        self._meshes.append(mesh)
        return len(self._meshes) - 1

    def __getitem__(self, handle: int) -> MeshData:
        return self._meshes[handle]

    def __len__(self) -> int:
        return len(self._meshes)

    def replace(self, handle: int, mesh: MeshData) -> None:
        self._meshes[handle] = mesh


def _same(a: MeshData, b: MeshData) -> bool:
    import numpy as np

    return (
        a.vertex_count == b.vertex_count
        and np.array_equal(a.indices, b.indices)
        and np.array_equal(a.positions, b.positions)
        and np.array_equal(a.normals, b.normals)
    )


class Meshes:
    """The world's meshes: `add(mesh)` and `load(path)` give the handle a `Mesh` component takes;
    `meshes[handle]` is the MeshData. `registry` is the renderer's MeshRegistry (or a MeshList)."""

    def __init__(self, registry: Any = None) -> None:
        self.registry = MeshList() if registry is None else registry
        self.files: dict[int, Path] = {}  # handle -> the model file `load` read it from (hot reload watches them)

    def add(self, mesh: MeshData) -> int:
        if not isinstance(mesh, MeshData):
            raise TypeError(f"Meshes.add takes a MeshData (render/assets/primitives.py makes some), not {mesh!r:.80}")
        return int(self.registry.add(mesh))

    def load(self, path: str | os.PathLike[str]) -> int:
        """A model file (OBJ, glTF/GLB, PLY, STL), every part as one mesh. A bad file is one
        UsageError naming it. For a model's parts with their own materials use
        render.model_loading.load_model(path, materials(world)) and `add` each part's mesh."""
        from .mesh_loading import load_mesh

        handle = self.add(load_mesh(path))
        self.files.setdefault(handle, Path(path).resolve())
        return handle

    def replace(self, handle: int, mesh: MeshData) -> None:
        """`mesh` under `handle`, where another was (hot reload: its file changed): entities
        drawing `handle` draw the new one from the next frame."""
        if not isinstance(mesh, MeshData):
            raise TypeError(f"Meshes.replace takes a MeshData, not {mesh!r:.80}")
        if not 0 <= handle < len(self.registry):
            raise KeyError(f"no mesh {handle!r}; there are {len(self.registry)}")
        self.registry.replace(handle, mesh)

    def __getitem__(self, handle: int) -> MeshData:
        entry = self.registry[handle]
        data: MeshData = getattr(entry, "data", entry)
        return data

    def __len__(self) -> int:
        return len(self.registry)

    def keep_on_cpu(self) -> None:
        """The registry is about to go (the run ends): keep its MeshData, same handles, so the
        world can still be saved and run again."""
        self.registry = MeshList([self[h] for h in range(len(self))])
