"""Saved scenes' meshes: the codec of the meshes `Mesh.handle` names (a session's MeshRegistry,
or a world's `Meshes` resource), saved by reference to their source (a primitive recipe, a model
file, normalized parts) when known, else by value, and made again on load within budgets that
refuse a hostile file before it allocates (docs/scene-format.md). Apart from scene_assets.py's
materials and environment codecs for size; scene_assets.py registers all three."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ...components.mesh import Mesh
from ...ecs.scene_file import SavedResource
from ...errors import UsageError
from .mesh_data import MeshData
from .meshes import Meshes
from .scene_codec_base import Prepared as _Prepared
from .scene_codec_base import doc_value as _doc

#: The vertices that the primitive recipes of one scene file may make, all together (docs/scene-format.md):
#: a 40 KB file once asked for eight million-vertex spheres (18 GB with their levels of detail). The
#: largest shape a stock demo makes has 2,145; a 511 x 511 sphere fits.
MAX_RECIPE_VERTICES = 1 << 18


@dataclass
class RecipeBudget:
    """What is left of MAX_RECIPE_VERTICES for one load: each recipe takes its share before it
    makes anything, so a hostile file is refused before it allocates."""

    left: int = MAX_RECIPE_VERTICES

    def take(self, vertices: int, what: str) -> None:
        if vertices > self.left:
            spent = MAX_RECIPE_VERTICES - self.left
            raise ValueError(
                f"{what} would make {vertices:,} vertices; a scene file's recipes may make at most "
                f"{MAX_RECIPE_VERTICES:,} in all ({spent:,} made already)"
            )
        self.left -= vertices


#: A mesh saved by value has at most this many vertices and triangles (a 16M-vertex mesh's arrays
#: are about 1 GiB): the arrays' sizes are checked before they are read, and saving refuses more.
MAX_SAVED_VERTICES = 1 << 24
MAX_SAVED_TRIANGLES = 1 << 24


class MeshSource(Protocol):
    """What MeshReferences needs of a mesh registry (MeshRegistry is one): the mesh (or an entry
    with `.data`) at a handle, and `add`, which returns the handle of a mesh."""

    def __getitem__(self, handle: int) -> Any: ...

    def __len__(self) -> int: ...

    def add(self, mesh: MeshData) -> int: ...


class MeshReferences:
    """Codec of the meshes that `Mesh.handle` names in `registry`. `by_value`: save every mesh's
    arrays, even those whose source could make them again."""

    name = "meshes"
    resource_types: tuple[Any, ...] = (Meshes,)  # a world's Meshes resource is what it saves

    def __init__(self, registry: MeshSource, *, by_value: bool = False) -> None:
        self.registry, self.by_value = registry, by_value

    def check_array(self, key: str, dtype: np.dtype, shape: tuple[int, ...]) -> None:
        """A mesh's array, before it is read: numbers, within MAX_SAVED_VERTICES/TRIANGLES."""
        part = key.rpartition("_")[2]
        width = {"positions": 3, "normals": 3, "uvs": 2, "tangents": 4, "indices": None}.get(part, -1)
        ok = dtype.kind in "uif" and dtype.itemsize <= 8
        if not ok or width == -1 or (width is None and len(shape) != 1) or (width and shape[1:] != (width,)):
            raise ValueError(f"mesh array {key} is {dtype} {shape}, not a mesh's {part}")
        _check_counts(key, shape[0] if width else 0, shape[0] // 3 if width is None else 0)

    def save(self, world: Any) -> SavedResource | None:
        used: set[int] = set()
        for table in world.tables:
            if table.count and table.has(Mesh):
                column = table.columns[(Mesh, "handle")][: table.count]
                top = int(column.max())
                hits = np.flatnonzero(np.bincount(column, minlength=top + 1)) if top < 1 << 20 else np.unique(column)
                used.update(hits.tolist())
        entries, arrays = [], {}
        for handle in sorted(used):
            if handle >= len(self.registry):
                raise ValueError(f"Mesh.handle {handle} is not a mesh of the registry ({len(self.registry)} meshes)")
            mesh: MeshData = getattr(self.registry[handle], "data", self.registry[handle])
            entry = {"handle": handle, "name": mesh.name, "vertices": mesh.vertex_count, "source": mesh.source}
            if mesh.source is None or self.by_value:
                _check_counts(f"mesh {handle} ({mesh.name})", mesh.vertex_count, mesh.triangle_count)
                entry["source"] = None
                for part in ("positions", "normals", "indices", "uvs", "tangents"):
                    arrays[f"mesh{handle}_{part}"] = getattr(mesh, part)
            entries.append(entry)
        return SavedResource({"meshes": entries}, arrays) if entries else None

    def read(self, saved: SavedResource, world: Any) -> _Prepared:
        doc = _doc(saved.doc, dict, "the meshes document")
        made: dict[int, MeshData] = {}
        cache: dict[str, Any] = {}  # a model file read once for all its parts
        budget = RecipeBudget()
        for i, entry in enumerate(_doc(doc.get("meshes"), list, "meshes")):
            entry = _doc(entry, dict, f"mesh {i}")
            handle = _doc(entry.get("handle"), int, f"mesh {i}'s handle")
            if not 0 <= handle < 1 << 20 or handle in made:
                raise ValueError(f"mesh handle {handle} is out of range or saved twice")
            if entry.get("source") is None:
                made[handle] = _mesh_arrays(saved.arrays, handle, str(entry.get("name", "mesh")))
            else:
                made[handle] = mesh_from_source(entry["source"], cache, budget=budget)
                count = entry.get("vertices")
                if _made_in_code(entry["source"]) and count != made[handle].vertex_count:
                    raise ValueError(
                        f"mesh {handle}: its source makes {made[handle].vertex_count} vertices, not {count}"
                    )
        lookup = np.full(max(made, default=-1) + 1, -1, np.int64)
        for handle, mesh in made.items():
            lookup[handle] = self.registry.add(mesh)  # the session's registry, not the world
        return _Prepared({(Mesh, "handle"): lookup}, lambda world: None)


class WorldMeshes:
    """Codec of the meshes of the world's own `Meshes` resource: MeshReferences over it, the
    default of World.save and World.load (registered below)."""

    name = MeshReferences.name
    resource_types = MeshReferences.resource_types
    check_array = MeshReferences.check_array

    def save(self, world: Any) -> SavedResource | None:
        found: Meshes | None = world.resources.get(Meshes)
        return None if found is None else MeshReferences(found).save(world)

    def read(self, saved: SavedResource, world: Any) -> _Prepared:
        found: Meshes | None = world.resources.get(Meshes)
        if found is None:
            raise ValueError(
                "the world it is loaded into has no Meshes resource to add its meshes to (load it into an "
                "App's world, or pass resources=scene_codecs(registry))"
            )
        return MeshReferences(found).read(saved, world)


def _check_counts(what: str, vertices: int, triangles: int) -> None:
    for count, name, limit in (
        (vertices, "vertices", MAX_SAVED_VERTICES),
        (triangles, "triangles", MAX_SAVED_TRIANGLES),
    ):
        if count > limit:
            raise ValueError(f"{what} has {count:,} {name}; a mesh saved by value has at most {limit:,}")


def _mesh_arrays(arrays: Mapping[str, np.ndarray], handle: int, name: str) -> MeshData:
    """A mesh saved by value."""
    get = {p: arrays.get(f"mesh{handle}_{p}") for p in ("positions", "normals", "indices", "uvs", "tangents")}
    positions, normals, indices = get["positions"], get["normals"], get["indices"]
    if positions is None or normals is None or indices is None:
        raise ValueError(f"mesh {handle} has neither a source nor its arrays")
    return MeshData.from_arrays(positions, normals, indices, name, get["uvs"], get["tangents"])


def _made_in_code(source: dict[str, Any]) -> bool:
    """Whether the recipe makes the same mesh every time (no file that may have changed since)."""
    if "primitive" in source:
        return True
    of = source.get("of")
    if "normalized" in source:
        return isinstance(of, dict) and _made_in_code(of)
    if "normalized_together" in source:
        return isinstance(of, list) and all(isinstance(o, dict) and _made_in_code(o) for o in of)
    return False


def mesh_from_source(
    source: Any, cache: dict[str, Any] | None = None, depth: int = 0, *, budget: RecipeBudget | None = None
) -> MeshData:
    """The mesh a MeshData.source recipe makes (ValueError for one that is not a recipe, or one
    past `budget`). `cache`: meshes made so far in this load, so a model's parts read its file
    once; `budget`: the vertices this load's primitive recipes may still make (default: a whole
    MAX_RECIPE_VERTICES)."""
    cache = {} if cache is None else cache
    budget = RecipeBudget() if budget is None else budget
    source = _doc(source, dict, "a mesh source")
    if depth > 8:
        raise ValueError("a mesh source nested more than 8 deep")
    key = json.dumps(source, sort_keys=True)
    if key not in cache:
        cache[key] = _made(source, cache, depth, budget)
    made: MeshData = cache[key]
    return made


def _made(source: dict[str, Any], cache: dict[str, Any], depth: int, budget: RecipeBudget) -> MeshData:
    from .mesh_data import normalized, normalized_together
    from .primitives import PRIMITIVES, primitive_vertices

    if "primitive" in source:
        name = _doc(source["primitive"], str, "a primitive's name")
        args = _doc(source.get("args", {}), dict, "a primitive's args")
        vertices = primitive_vertices(name, args)  # unknown names and arguments, counts that are no integers
        budget.take(vertices, f"the {name} recipe {json.dumps(args)[:120]}")
        return PRIMITIVES[name](**args)  # which checks every argument's value
    if "file" in source:
        from .mesh_loading import load_mesh
        from .model_loading import model_part

        file = _doc(source["file"], str, "a mesh file")
        try:
            if "part" in source:
                return model_part(file, _doc(source["part"], int, "a model part"))
            return load_mesh(file)
        except UsageError as exc:
            raise ValueError(str(exc)) from None
    if "normalized" in source:
        size = _doc(source["normalized"], float, "a normalized size")
        return normalized(mesh_from_source(source.get("of"), cache, depth + 1, budget=budget), size)
    if "normalized_together" in source:
        size = _doc(source["normalized_together"], float, "a normalized size")
        of = _doc(source.get("of"), list, "the parts normalized together")
        part = _doc(source.get("part"), int, "a part")
        if not 0 <= part < len(of):
            raise ValueError(f"part {part} of {len(of)} parts normalized together")
        key = json.dumps({"normalized_together": size, "of": of}, sort_keys=True)
        if key not in cache:
            cache[key] = normalized_together([mesh_from_source(o, cache, depth + 1, budget=budget) for o in of], size)
        together: list[MeshData] = cache[key]
        return together[part]
    raise ValueError(f"not a mesh source: {str(source)[:80]}")
