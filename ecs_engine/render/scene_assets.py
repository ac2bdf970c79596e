"""Saved scenes' render assets: the codecs (ecs/scene_file.py's ResourceCodec) that save a world's
materials and environment and a session's meshes, kept out of the ECS core, which knows no
renderer. Importing this module registers three codecs as defaults of World.save and World.load:
materials, environment, and the meshes of the world's `Meshes` resource (render/meshes.py; an App
puts one in its world, so `world.save(path)` there keeps its meshes with no extra argument). A
world without one saves no meshes and refuses to load a file that has some; a registry that is
not a world resource is passed as `scene_codecs(registry)`.

- materials (`Materials` resource): every material as JSON (the dataclass's fields), texture
  fields as indices into the saved textures, whose pixels are arrays (by value: a `Texture` does
  not keep the file it came from). On load they join the target's materials (an equal material,
  such as the default palette, is reused) and `Mesh.material` is rewritten to the new handles.
- environment (`Environment` resource): its settings as JSON; a source that is a path (or six)
  by reference, pixels as an array. Loading replaces the target's environment.
- meshes (`Mesh.handle`, the session's MeshRegistry): per handle the entities use, its name,
  counts and `MeshData.source` (a primitive and its arguments, a model file, normalized...) when
  known, else its arrays. On load each is made again (or read), added to the registry (which
  reuses an equal mesh) and `Mesh.handle` rewritten. The registry may gain meshes even when the
  load then fails; the world does not change.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ..components.environment import Environment
from ..components.mesh import Mesh
from ..ecs.scene_file import Remaps, ResourceCodec, SavedResource, register_codec
from ..errors import UsageError
from ..user_files import IMAGE, check_user_file
from .environment_maps import check_cube_size, environment_texels
from .materials import DEFAULT_PALETTE, TEXTURE_FIELDS, Material, Materials, materials
from .mesh_data import MeshData
from .meshes import Meshes
from .textures import ImageError, Texture, read_image, texture_size_error

__all__ = [
    "MAX_RECIPE_VERTICES",
    "EnvironmentCodec",
    "MaterialsCodec",
    "MeshReferences",
    "RecipeBudget",
    "WorldMeshes",
    "mesh_from_source",
    "scene_codecs",
]

MATERIAL_FIELDS = tuple(f.name for f in dataclasses.fields(Material))
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


_BOOL_FIELDS = frozenset(f.name for f in dataclasses.fields(Material) if isinstance(f.default, bool))
#: A mesh saved by value has at most this many vertices and triangles (a 16M-vertex mesh's arrays
#: are about 1 GiB): the arrays' sizes are checked before they are read, and saving refuses more.
MAX_SAVED_VERTICES = 1 << 24
MAX_SAVED_TRIANGLES = 1 << 24


def _doc(value: Any, kind: type, what: str) -> Any:
    """`value` if it is a `kind` (a float may be written as an int; a bool is no number)."""
    kinds = (int, float) if kind is float else kind
    if not isinstance(value, kinds) or (isinstance(value, bool) and kind is not bool):
        raise ValueError(f"{what} must be a {kind.__name__}, got {str(value)[:80]}")
    return float(value) if isinstance(value, (int, float)) and kind is float else value


@dataclass
class _Prepared:
    """A resource planned against the target world: lookup tables now, changes at commit."""

    tables: Remaps
    apply: Any  # (world) -> None

    def remaps(self) -> Remaps:
        return self.tables

    def commit(self, world: Any) -> None:
        self.apply(world)


# ------------------------------------------------------------------------------- materials
class MaterialsCodec:
    name = "materials"
    resource_types: tuple[Any, ...] = (Materials,)

    def check_array(self, key: str, dtype: np.dtype, shape: tuple[int, ...]) -> None:
        """A texture's pixels, before they are read: RGBA8 of at most MAX_TEXTURE_PIXELS."""
        if dtype != np.uint8 or len(shape) != 3 or shape[2] != 4:
            raise ValueError(f"{key} is {dtype} {shape}, not RGBA8 pixels (height, width, 4)")
        too_large = texture_size_error(shape[1], shape[0])
        if too_large:
            raise ValueError(f"{key}: {too_large}")

    def save(self, world: Any) -> SavedResource | None:
        found: Materials | None = world.resources.get(Materials)
        if found is None:
            return None
        textures: dict[int, int] = {}  # handle -> index among the saved ones
        docs = []
        for material in found:
            doc = dataclasses.asdict(material)
            for name in TEXTURE_FIELDS:
                if doc[name] is not None:
                    doc[name] = textures.setdefault(doc[name], len(textures))
            docs.append(doc)
        saved = [found.textures[h] for h in textures]
        texture_docs = [{"name": t.name, "color": t.color, "file": t.source} for t in saved]
        arrays = {f"texture{i}": t.pixels for i, t in enumerate(saved) if t.source is None}  # by value
        return SavedResource({"materials": docs, "textures": texture_docs}, arrays)

    def read(self, saved: SavedResource, world: Any) -> _Prepared:
        doc = _doc(saved.doc, dict, "the materials document")
        texture_docs = _doc(doc.get("textures"), list, "textures")
        textures = []
        for i, t in enumerate(texture_docs):
            t = _doc(t, dict, f"texture {i}")
            name, color = str(t.get("name", "")), _doc(t.get("color"), bool, "color")
            textures.append(_texture(i, name, color, t.get("file"), saved.arrays.get(f"texture{i}")))
        target: Materials | None = world.resources.get(Materials)
        have_textures = [] if target is None else [target.textures[h] for h in range(len(target.textures))]
        new_textures, texture_handles = [], []
        for t in textures:  # an equal texture already there is reused
            same = [h for h, o in enumerate(have_textures) if _same_texture(o, t)]
            if not same:
                have_textures.append(t)
                new_textures.append(t)
            texture_handles.append(same[0] if same else len(have_textures) - 1)
        existing = list(DEFAULT_PALETTE if target is None else target)  # what materials(world) will hold
        have = {m: h for h, m in reversed(list(enumerate(existing)))}
        new_materials: list[Material] = []
        handles: list[int] = []
        for i, m in enumerate(_doc(doc.get("materials"), list, "materials")):
            fields = dict(_doc(m, dict, f"material {i}"))
            unknown = set(fields) - set(MATERIAL_FIELDS)
            if unknown:
                raise ValueError(f"material {i} has unknown fields {sorted(unknown)[:5]}")
            for name, value in fields.items():  # Material takes true for 1.0: a file may not
                values = value if isinstance(value, list) else [value]
                if name not in _BOOL_FIELDS and any(isinstance(v, bool) for v in values):
                    raise ValueError(f"material {i}'s {name} takes numbers, not {str(value)[:80]}")
            _doc(fields.get("name", ""), str, f"material {i}'s name")
            for name in TEXTURE_FIELDS:
                if fields.get(name) is not None:
                    index = _doc(fields[name], int, f"material {i}'s {name}")
                    if not 0 <= index < len(textures):
                        raise ValueError(f"material {i}'s {name} names no saved texture ({index})")
                    fields[name] = texture_handles[index]
            material = Material(**fields)
            if material not in have:  # an equal one (the default palette) is reused
                have[material] = len(existing) + len(new_materials)
                new_materials.append(material)
            handles.append(have[material])

        def apply(world: Any) -> None:
            registry = materials(world)
            for t in new_textures:
                registry.textures.add(t)
            for m in new_materials:
                registry.add(m)

        return _Prepared({(Mesh, "material"): np.array(handles, np.int64)}, apply)


def _environment_check(check: Any) -> None:
    """environment_maps' check, its UsageError as the ValueError codecs raise."""
    try:
        check()
    except UsageError as exc:
        raise ValueError(str(exc)) from None


def _regular(path: str) -> None:
    """An environment file that is there must be a regular file: loaded at the first frame, a
    FIFO or a device would hang it (one missing is reported then, as before)."""
    if os.path.lexists(path):
        try:
            check_user_file(path, IMAGE)
        except OSError as exc:
            raise ValueError(f"the environment's path {exc}") from None


def _texture(i: int, name: str, color: bool, file: Any, pixels: np.ndarray | None) -> Texture:
    """Saved texture `i`: read again from its file (by reference) or from its pixels (by value)."""
    if file is not None:
        path = Path(_doc(file, str, f"texture {i}'s file"))
        try:
            return Texture(name, read_image(path), color, str(path))
        except ImageError as exc:
            raise ValueError(f"texture {i} ({path}): {exc}") from None
    if pixels is None or pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] != 4:
        raise ValueError(f"texture {i} has neither a file nor RGBA8 pixels")
    return Texture(name, pixels, color)


def _same_texture(a: Texture, b: Texture) -> bool:
    same_file = a.source is not None and a.source == b.source
    return a.name == b.name and a.color == b.color and (same_file or np.array_equal(a.pixels, b.pixels))


# ----------------------------------------------------------------------------- environment
class EnvironmentCodec:
    name = "environment"
    resource_types: tuple[Any, ...] = (Environment,)

    def check_array(self, key: str, dtype: np.dtype, shape: tuple[int, ...]) -> None:
        """The pixels, before they are read: numbers, at most MAX_SOURCE_TEXELS of them."""
        if dtype.kind not in "uf" or dtype.itemsize > 8 or len(shape) not in (3, 4):
            raise ValueError(f"the environment's {key} are {dtype} {shape}, not (H, 2H, 3) or (6, S, S, 3) numbers")
        _environment_check(lambda: environment_texels(shape, key))

    def save(self, world: Any) -> SavedResource | None:
        env: Environment | None = world.resources.get(Environment)
        if env is None:
            return None
        size = None if env.size is None else int(env.size)
        settings = {"intensity": env.intensity, "sky": bool(env.sky), "ambient": bool(env.ambient), "size": size}
        if isinstance(env.source, np.ndarray):  # one a load would refuse is not saved
            _environment_check(lambda: environment_texels(env.source.shape, "pixels"))
            return SavedResource(settings | {"source": {"pixels": "pixels"}}, {"pixels": env.source})
        if isinstance(env.source, (str, Path)):
            return SavedResource(settings | {"source": {"path": str(env.source)}})
        return SavedResource(settings | {"source": {"paths": [str(p) for p in env.source]}})

    def read(self, saved: SavedResource, world: Any) -> _Prepared:
        doc = _doc(saved.doc, dict, "the environment document")
        source = _doc(doc.get("source"), dict, "the environment's source")
        if "pixels" in source:
            value: Any = saved.arrays.get("pixels")
            if value is None or value.dtype.kind not in "uf":
                raise ValueError("the environment's pixels are missing or not numbers")
        elif "path" in source:
            value = _doc(source["path"], str, "the environment's path")
            _regular(value)
        else:
            value = [_doc(p, str, "an environment path") for p in _doc(source.get("paths"), list, "paths")]
            for path in value[:6]:
                _regular(path)
        size = doc.get("size")
        if size is not None:
            _environment_check(lambda: check_cube_size(_doc(size, int, "size")))
        env = Environment(
            value,
            _doc(doc.get("intensity"), float, "intensity"),
            _doc(doc.get("sky"), bool, "sky"),
            _doc(doc.get("ambient"), bool, "ambient"),
            None if size is None else _doc(size, int, "size"),
        )
        return _Prepared({}, lambda world: world.resources.__setitem__(Environment, env))


# ---------------------------------------------------------------------------------- meshes
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
    from ..errors import UsageError
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


def scene_codecs(meshes: MeshSource | None = None) -> list[ResourceCodec]:
    """Every stock codec, with the meshes of `meshes` (a session's MeshRegistry) when given."""
    codecs: list[ResourceCodec] = [MaterialsCodec(), EnvironmentCodec()]
    if meshes is not None:
        codecs.append(MeshReferences(meshes))
    return codecs


register_codec(MaterialsCodec())
register_codec(EnvironmentCodec())
register_codec(WorldMeshes())
