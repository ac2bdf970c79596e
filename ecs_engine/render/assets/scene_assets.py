"""Saved scenes' render assets: the codecs (ecs/scene_file.py's ResourceCodec) that save a world's
materials and environment and a session's meshes, kept out of the ECS core, which knows no
renderer. Importing this module registers three codecs as defaults of World.save and World.load:
materials, environment, and the meshes of the world's `Meshes` resource (render/assets/meshes.py; an App
puts one in its world, so `world.save(path)` there keeps its meshes with no extra argument). A
world without one saves no meshes and refuses to load a file that has some; a registry that is
not a world resource is passed as `scene_codecs(registry)`.

- materials (`Materials` resource): every material as JSON (the dataclass's fields), texture
  fields as indices into the saved textures: a file's by reference, others' pixels as arrays, a
  render target (Textures.render_target: a camera draws it) by its name and size. On load they
  join the target's materials (an equal material, such as the default palette, is reused; a
  render target of that name too) and `Mesh.material` is rewritten to the new handles.
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
import os
from pathlib import Path
from typing import Any

import numpy as np

from ...components.camera import render_texture_size_error
from ...components.environment import Environment
from ...components.mesh import Mesh
from ...ecs.scene_file import ResourceCodec, SavedResource, register_codec
from ...errors import UsageError
from ...user_files import IMAGE, check_user_file
from ..lighting.environment_maps import check_cube_size, environment_texels
from .materials import DEFAULT_PALETTE, TEXTURE_FIELDS, Material, Materials, materials
from .scene_codec_base import Prepared as _Prepared
from .scene_codec_base import doc_value as _doc
from .scene_meshes import (
    MAX_RECIPE_VERTICES,
    MeshReferences,
    MeshSource,
    RecipeBudget,
    WorldMeshes,
    mesh_from_source,
)
from .textures import ImageError, RenderTarget, Texture, read_image, texture_size_error

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
_BOOL_FIELDS = frozenset(f.name for f in dataclasses.fields(Material) if isinstance(f.default, bool))


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
        texture_docs: list[dict[str, Any]] = []
        arrays = {}
        for i, handle in enumerate(textures):
            t, target = found.textures[handle], found.textures.render_target_of(handle)
            if target is not None:  # its camera draws it: its name and size, not its black texel
                texture_docs.append({"name": target.name, "render_target": [target.width, target.height]})
                continue
            texture_docs.append({"name": t.name, "color": t.color, "file": t.source})
            if t.source is None:  # by value
                arrays[f"texture{i}"] = t.pixels
        return SavedResource({"materials": docs, "textures": texture_docs}, arrays)

    def read(self, saved: SavedResource, world: Any) -> _Prepared:
        doc = _doc(saved.doc, dict, "the materials document")
        texture_docs = _doc(doc.get("textures"), list, "textures")
        textures: list[Texture | RenderTarget] = []
        for i, t in enumerate(texture_docs):
            t = _doc(t, dict, f"texture {i}")
            if "render_target" in t:
                textures.append(_render_target(i, t))
                continue
            name, color = str(t.get("name", "")), _doc(t.get("color"), bool, "color")
            textures.append(_texture(i, name, color, t.get("file"), saved.arrays.get(f"texture{i}")))
        target: Materials | None = world.resources.get(Materials)
        # the target's textures; its render targets by name alone (their texel is no picture)
        have_textures: list[Texture | RenderTarget] = []
        if target is not None:
            for h in range(len(target.textures)):
                drawn = target.textures.render_target_of(h)
                have_textures.append(target.textures[h] if drawn is None else drawn)
        new_textures, texture_handles = [], []
        for t in textures:  # an equal texture (a render target of that name) already there is reused
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
            for t in new_textures:  # in order: the handles above count them
                if isinstance(t, RenderTarget):
                    registry.textures.render_target(t.name, t.width, t.height)
                else:
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


def _render_target(i: int, doc: dict[str, Any]) -> RenderTarget:
    """Saved texture `i`, a render target: its name and size (the handle is given on load)."""
    name = _doc(doc.get("name"), str, f"texture {i}'s name")
    size = _doc(doc["render_target"], list, f"texture {i}'s render_target")
    if len(size) != 2 or not name:
        raise ValueError(f"texture {i}: a render target is a name and [width, height], got {name!r} {size[:4]}")
    refused = render_texture_size_error(name, size[0], size[1])
    if refused:
        raise ValueError(f"texture {i}: {refused}")
    return RenderTarget(name, -1, int(size[0]), int(size[1]))


def _same_texture(a: Texture | RenderTarget, b: Texture | RenderTarget) -> bool:
    """The same pixels (or file), or the same render target: a name is one render target, and
    one asked for at another size is refused (Textures.render_target's one message)."""
    if isinstance(a, RenderTarget) or isinstance(b, RenderTarget):
        if not (isinstance(a, RenderTarget) and isinstance(b, RenderTarget) and a.name == b.name):
            return False
        if (a.width, a.height) != (b.width, b.height):
            raise ValueError(
                f"render texture {a.name!r} is {a.width} x {a.height} pixels here and {b.width} x {b.height} "
                "in the file: one name is one image"
            )
        return True
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


def scene_codecs(meshes: MeshSource | None = None) -> list[ResourceCodec]:
    """Every stock codec, with the meshes of `meshes` (a session's MeshRegistry) when given."""
    codecs: list[ResourceCodec] = [MaterialsCodec(), EnvironmentCodec()]
    if meshes is not None:
        codecs.append(MeshReferences(meshes))
    return codecs


register_codec(MaterialsCodec())
register_codec(EnvironmentCodec())
register_codec(WorldMeshes())
