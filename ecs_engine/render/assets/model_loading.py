"""Models with their own materials: a file's geometry split by material, each material (and its
textures) added to a world's `Materials`.

- glTF / GLB: the metallic-roughness material (`cook_torrance`) with its five textures, factors,
  alpha mode and cutoff, as trimesh reads them; which image each texture names comes from the
  file's JSON, so an image that cannot be read is named in the warning.
- OBJ: the .mtl libraries it names (mtl.py), as `blinn_phong` materials.
- PLY, STL, and parts without a material: `material` None (the caller picks one).

A texture that is missing or broken leaves the model loading: one warning names the image and
the fallback checkerboard shows where it was meant to be. glTF `BLEND` and OBJ `d < 1` become
blended materials (set_aside_pass.py).
"""

from __future__ import annotations

import logging
import os
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import UsageError
from ...user_files import MODEL, read_user_file
from ...user_json import parse_json
from .materials import MAX_SHININESS, Material, Materials
from .mesh_data import MeshData
from .mesh_loading import assemble, read_parts
from .mtl import MtlMaterial, MtlTexture, mtl_libraries, read_mtl
from .textures import ImageError, Texture, pixels_of

__all__ = ["ModelPart", "load_model", "model_part"]

log = logging.getLogger("ecs_engine")

# glTF texture slot (trimesh's PBRMaterial attribute and the JSON key) -> Material field, sRGB?
GLTF_TEXTURES = {
    "baseColorTexture": ("base_color_texture", True),
    "metallicRoughnessTexture": ("metallic_roughness_texture", False),
    "normalTexture": ("normal_texture", False),
    "emissiveTexture": ("emissive_texture", True),
    "occlusionTexture": ("occlusion_texture", False),
}


@dataclass(frozen=True)
class ModelPart:
    mesh: MeshData
    material: int | None  # a handle in the Materials given to load_model; None: the file gave none


def load_model(
    path: str | os.PathLike[str], registry: Materials, *, max_triangles: int | None = None
) -> list[ModelPart]:
    """The file's parts, one per material, in file order. Geometry problems raise UsageError as
    `load_mesh` does; material and texture problems only warn. Each part's mesh records its
    source ({"file", "part"}: saved scenes refer to it instead of copying it)."""
    file, parts, trimesh_materials = read_parts(path, max_triangles)
    converter = _converter(file, registry)
    meshes = _part_meshes(file, parts, trimesh_materials)
    return [ModelPart(mesh, None if material is None else converter(material)) for material, mesh in meshes]


def model_part(path: str | os.PathLike[str], part: int) -> MeshData:
    """Part `part` of the model at `path`, as load_model makes it (no materials read): what a
    saved scene's {"file": path, "part": k} source names. UsageError for a part the file lacks."""
    file, parts, trimesh_materials = read_parts(path)
    meshes = _part_meshes(file, parts, trimesh_materials)
    if not 0 <= part < len(meshes):
        raise UsageError(f"{file}: has {len(meshes)} parts, not a part {part}")
    return meshes[part][1]


def _part_meshes(file: Path, parts: list[Any], trimesh_materials: list[object | None]) -> list[tuple[Any, MeshData]]:
    """(trimesh material, mesh) per material, in file order; a material whose triangles are all
    degenerate is left out (UsageError when all are)."""
    groups: dict[int, tuple[object | None, list[int]]] = {}
    for i, material in enumerate(trimesh_materials):
        groups.setdefault(id(material), (material, []))[1].append(i)
    out: list[tuple[Any, MeshData]] = []
    error: UsageError | None = None
    for material, indices in groups.values():
        try:
            source = {"file": str(file.resolve()), "part": len(out)}
            mesh = assemble(file, [parts[i] for i in indices], f"{file.stem}:{_name(material) or 'default'}", source)
        except UsageError as exc:  # this material's triangles are all degenerate: the others may not be
            error = exc
            continue
        out.append((material, mesh))
    if not out:
        assert error is not None
        raise error
    return out


def _name(material: object | None) -> str | None:
    return getattr(material, "name", None)


def _converter(file: Path, registry: Materials) -> Any:
    suffix = file.suffix.lower()
    if suffix in (".gltf", ".glb"):
        return _GltfMaterials(file, registry)
    if suffix == ".obj":
        return _ObjMaterials(file, registry)
    return lambda material: None


class _ObjMaterials:
    def __init__(self, file: Path, registry: Materials) -> None:
        self.registry = registry
        self.library: dict[str, MtlMaterial] = {}
        try:
            text = read_user_file(file, MODEL).decode("utf-8", errors="replace")
        except OSError as exc:  # read a moment ago by read_parts: gone or changed since
            log.warning("%s: cannot be read again for its materials (%s); drawn with defaults", file, exc)
            text = ""
        for mtl in mtl_libraries(text, file):
            self.library.update(read_mtl(mtl, named_by=str(file)))
        self.handles: dict[str, int | None] = {}

    def __call__(self, material: object) -> int | None:
        name = _name(material)
        if name is None or name not in self.library:
            return None
        if name not in self.handles:
            self.handles[name] = self._add(self.library[name])
        return self.handles[name]

    def _add(self, m: MtlMaterial) -> int:
        textures = self.registry.textures
        maps = m.maps
        opacity = _unit(m.opacity)
        emissive = m.emissive
        if "emissive" in maps and not any(emissive):
            emissive = (1.0, 1.0, 1.0)  # map_Ke alone: the map is the emission
        return self.registry.add(
            Material(
                m.name,
                "blinn_phong",
                (*_rgb(m.diffuse, _unit), opacity),
                alpha_mode="blend" if opacity < 1.0 else "opaque",
                shininess=float(np.clip(m.shininess, 1.0, MAX_SHININESS)),
                specular=float(np.clip(np.mean(m.specular), 0.0, 1.0)),
                emissive=_rgb(emissive, _positive),
                base_color_texture=_load(textures, maps.get("diffuse"), True),
                normal_texture=_load(textures, maps.get("normal"), False),
                normal_scale=maps["normal"].scale if "normal" in maps else 1.0,
                emissive_texture=_load(textures, maps.get("emissive"), True),
            )
        )


def _load(textures: Any, texture: MtlTexture | None, color: bool) -> int | None:
    if texture is None:
        return None
    named_by = None if texture.library is None else str(texture.library)
    handle: int = textures.load(texture.path, color=color, named_by=named_by)
    return handle


def _unit(value: float) -> float:
    return float(np.clip(value, 0.0, 1.0)) if np.isfinite(value) else 0.0


def _positive(value: float) -> float:
    return max(float(value), 0.0) if np.isfinite(value) else 0.0


def _rgb(values: Any, clean: Any) -> tuple[float, float, float]:
    r, g, b = (clean(float(v)) for v in list(values)[:3])
    return (r, g, b)


class _GltfMaterials:
    def __init__(self, file: Path, registry: Materials) -> None:
        self.file = file
        self.registry = registry
        self.handles: dict[int, int] = {}
        self.images: dict[tuple[int, bool], int] = {}  # (id of trimesh's image, sRGB) -> texture handle
        self.warned: set[str] = set()
        self.header = _gltf_json(file)

    def __call__(self, material: object) -> int:
        key = id(material)
        if key not in self.handles:
            self.handles[key] = self._add(material)
        return self.handles[key]

    def _add(self, pbr: Any) -> int:
        name = _name(pbr) or "material"
        fields: dict[str, Any] = {}
        declared = self._declared(name)  # what the file's JSON says the material's textures are
        for slot, (field, color) in GLTF_TEXTURES.items():
            image = getattr(pbr, slot, None)
            if image is not None:
                fields[field] = self._texture(image, color, name, slot)
            elif slot in declared:
                self._warn(declared[slot], name)
                fields[field] = self.registry.textures.fallback
        factor = getattr(pbr, "baseColorFactor", None)
        base = (1.0, 1.0, 1.0, 1.0) if factor is None else tuple(np.asarray(factor, np.float64) / 255.0)
        mode = str(getattr(pbr, "alphaMode", None) or "OPAQUE").upper()
        emissive = getattr(pbr, "emissiveFactor", None)
        return self.registry.add(
            Material(
                name,
                "cook_torrance",
                (*_rgb(base[:3], _unit), _unit(base[3])),
                metallic=_unit(_or(getattr(pbr, "metallicFactor", None), 1.0)),
                roughness=_unit(_or(getattr(pbr, "roughnessFactor", None), 1.0)),
                emissive=(0.0, 0.0, 0.0) if emissive is None else _rgb(emissive, _positive),
                alpha_mode={"MASK": "mask", "BLEND": "blend"}.get(mode, "opaque"),
                alpha_cutoff=_unit(_or(getattr(pbr, "alphaCutoff", None), 0.5)),
                double_sided=bool(getattr(pbr, "doubleSided", False)),
                normal_scale=self._normal_scale(name),
                **fields,
            )
        )

    def _texture(self, image: object, color: bool, material: str, slot: str) -> int:
        key = id(image)
        if (key, color) not in self.images:
            try:
                handle = self.registry.textures.add(Texture(f"{material}.{slot}", pixels_of(image), color))
            except (ImageError, ValueError, OSError) as exc:
                self._warn(f"the {slot} image ({exc})", material)
                handle = self.registry.textures.fallback
            self.images[(key, color)] = handle
        return self.images[(key, color)]

    def _declared(self, material: str) -> dict[str, str]:
        """The texture slots the file's JSON gives this material, each with its image's uri or
        a description of the embedded image."""
        header = self.header
        out: dict[str, str] = {}
        for m in header.get("materials", []):
            if not isinstance(m, dict) or m.get("name", "material") != material:
                continue
            slots = {**m.get("pbrMetallicRoughness", {}), **m}
            for slot in GLTF_TEXTURES:
                info = slots.get(slot)
                if isinstance(info, dict) and isinstance(info.get("index"), int):
                    out[slot] = self._image_name(info["index"])
        return out

    def _image_name(self, texture_index: int) -> str:
        try:
            source = self.header["textures"][texture_index]["source"]
            image = self.header["images"][source]
        except (KeyError, IndexError, TypeError):
            return f"texture {texture_index}"
        uri = image.get("uri")
        if isinstance(uri, str) and not uri.startswith("data:"):
            return str(self.file.parent / uri)
        return f"embedded image {source}"

    def _normal_scale(self, material: str) -> float:
        for m in self.header.get("materials", []):
            if isinstance(m, dict) and m.get("name", "material") == material:
                scale = m.get("normalTexture", {}).get("scale", 1.0)
                if isinstance(scale, (int, float)) and np.isfinite(scale) and abs(scale) <= 1e3:
                    return float(scale)
        return 1.0

    def _warn(self, what: str, material: str) -> None:
        if what not in self.warned:
            self.warned.add(what)
            log.warning(
                "%s: %s of material %r cannot be read; drawn with the fallback texture", self.file, what, material
            )


def _or(value: object, default: float) -> float:
    return default if value is None else float(value)  # type: ignore[arg-type]


def _gltf_json(file: Path) -> dict[str, Any]:
    """The JSON of a .gltf, or of a .glb's first chunk; {} if unreadable (trimesh read it already)."""
    try:
        data = read_user_file(file, MODEL)
        if file.suffix.lower() == ".glb":
            length, kind = struct.unpack_from("<II", data, 12)
            if kind != 0x4E4F534A:  # "JSON"
                return {}
            data = data[20 : 20 + length]
        found = parse_json(data)
    except (OSError, ValueError, struct.error):
        return {}
    return found if isinstance(found, dict) else {}
