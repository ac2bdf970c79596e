"""A glTF mesh's primitives as the engine's meshes (MeshData), and its materials as Materials.

A primitive without NORMAL gets flat normals, as the specification asks; triangle strips and
fans become triangle lists; points and lines are left out with one warning (the renderer draws
triangles). Textures that cannot be read warn and use the fallback, as models' do.
"""

from __future__ import annotations

import io
import logging
from typing import Any

import numpy as np

from ..materials import Material, Materials
from ..mesh_data import MeshData
from ..model_loading import GLTF_TEXTURES
from ..morph_targets import MAX_MORPH_TARGETS, MorphTargets
from ..skin_weights import SkinWeights
from ..textures import ImageError, Texture, pixels_of
from .document import GltfDocument, data_uri

log = logging.getLogger("ecs_engine")

TRIANGLES, STRIP, FAN = 4, 5, 6
_MODES = {0: "points", 1: "lines", 2: "line loops", 3: "line strips"}


def primitive_mesh(document: GltfDocument, mesh: int, index: int) -> MeshData | None:
    """Primitive `index` of mesh `mesh` as MeshData, or None for points and lines (warned)."""
    here = f"meshes[{mesh}].primitives[{index}]"
    primitive = document.item("meshes", mesh, "mesh")["primitives"][index]
    mode = primitive.get("mode", TRIANGLES)
    if mode in _MODES:
        log.warning("%s: %s draws %s, which are left out (triangles only)", document.file, here, _MODES[mode])
        return None
    if mode not in (TRIANGLES, STRIP, FAN):
        raise document.error(f"{here}.mode", f"is {mode!r}, not a glTF primitive mode (0 to 6)")
    attributes = primitive.get("attributes")
    if not isinstance(attributes, dict) or "POSITION" not in attributes:
        raise document.error(f"{here}.attributes", "has no POSITION")
    positions = _attribute(document, attributes, "POSITION", here, (3,))
    n = len(positions)
    normals = _attribute(document, attributes, "NORMAL", here, (3,), n) if "NORMAL" in attributes else None
    uvs = _attribute(document, attributes, "TEXCOORD_0", here, (2,), n) if "TEXCOORD_0" in attributes else None
    if "indices" in primitive:
        where = f"{here}.indices"
        indices = document.accessor(document.number(primitive, "indices", here), where)
        if indices.dtype.kind != "u" or indices.ndim != 1:
            raise document.error(where, "is not an accessor of unsigned integer scalars")
        indices = indices.astype(np.uint32)
        if len(indices) and int(indices.max()) >= n:
            raise document.error(where, f"index {int(indices.max())} is past the primitive's {n} vertices")
    else:
        indices = np.arange(n, dtype=np.uint32)
    skin = _skin_weights(document, attributes, here, n)
    morph = _morph_deltas(document, primitive, here, n)
    triangles = _triangles(indices, mode)
    if not len(triangles):
        raise document.error(here, "has no whole triangle")
    if normals is None:  # flat: each triangle's own vertices
        corners = triangles.reshape(-1)
        positions, uvs = positions[corners], None if uvs is None else uvs[corners]
        skin = None if skin is None else (skin[0][corners], skin[1][corners])
        morph = None if morph is None else (morph[0][:, corners], None, None)  # flat: no normals to morph
        normals = np.repeat(_face_normals(positions.reshape(-1, 3, 3)), 3, axis=0)
        triangles = np.arange(len(positions), dtype=np.uint32).reshape(-1, 3)
    name = str(document.item("meshes", mesh, "mesh").get("name", f"mesh{mesh}"))
    source = {"file": str(document.file.resolve()), "mesh": mesh, "primitive": index}
    return MeshData.from_arrays(
        positions.astype(np.float32),
        normals.astype(np.float32),
        triangles.reshape(-1),
        f"{document.file.stem}:{name}:{index}",
        uvs=None if uvs is None else uvs.astype(np.float32),
        source=source,
        skin=None if skin is None else _weights(document, *skin, here),
        morph=None if morph is None else _morph(document, mesh, morph, here),
    )


def _morph_deltas(
    document: GltfDocument, primitive: dict[str, Any], here: str, count: int
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None] | None:
    """The primitive's targets' POSITION, NORMAL and TANGENT deltas ((T, V, 3) each; None for an
    attribute no target has), or None without targets."""
    targets = primitive.get("targets")
    if targets is None:
        return None
    if not isinstance(targets, list) or not targets or not all(isinstance(t, dict) for t in targets):
        raise document.error(f"{here}.targets", "is not a non-empty array of objects")
    if len(targets) > MAX_MORPH_TARGETS:
        many = f"has {len(targets)} morph targets; at most {MAX_MORPH_TARGETS} are drawn"
        raise document.error(f"{here}.targets", many)
    out: list[np.ndarray | None] = []
    for name in ("POSITION", "NORMAL", "TANGENT"):
        if not any(name in t for t in targets):
            out.append(None)
            continue
        deltas = np.zeros((len(targets), count, 3), np.float32)
        for k, target in enumerate(targets):
            if name in target:
                deltas[k] = _attribute(document, target, name, f"{here}.targets[{k}]", (3,), count, inside="")
        out.append(deltas)
    positions = out[0] if out[0] is not None else np.zeros((len(targets), count, 3), np.float32)
    return positions, out[1], out[2]


def _morph(document: GltfDocument, mesh: int, deltas: tuple[Any, Any, Any], here: str) -> MorphTargets:
    entry = document.item("meshes", mesh, "mesh")
    count = len(deltas[0])
    weights = document.floats(entry, "weights", f"meshes[{mesh}]", count, [0.0] * count) if "weights" in entry else None
    try:
        return MorphTargets.of(deltas[0], deltas[1], deltas[2], weights, "morph targets")
    except ValueError as exc:
        raise document.error(f"{here}.targets", str(exc).removeprefix("morph targets: ")) from None


def _skin_weights(
    document: GltfDocument, attributes: dict[str, Any], here: str, count: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """JOINTS_0/1 and WEIGHTS_0/1 side by side ((count, 4 or 8) each), or None without JOINTS_0."""
    if "JOINTS_0" not in attributes and "WEIGHTS_0" not in attributes:
        return None
    sets = [k for k in (0, 1) if f"JOINTS_{k}" in attributes or f"WEIGHTS_{k}" in attributes]
    if sets != list(range(len(sets))):
        raise document.error(f"{here}.attributes", "has JOINTS_1 or WEIGHTS_1 without JOINTS_0 and WEIGHTS_0")
    joints, weights = [], []
    for k in sets:
        for name in (f"JOINTS_{k}", f"WEIGHTS_{k}"):
            if name not in attributes:
                other = f"WEIGHTS_{k}" if name.startswith("JOINTS") else f"JOINTS_{k}"
                raise document.error(f"{here}.attributes", f"has {other} without {name}")
        where = f"{here}.attributes.JOINTS_{k}"
        j = document.accessor(document.number(attributes, f"JOINTS_{k}", f"{here}.attributes"), where)
        if j.dtype.kind != "u" or j.shape[1:] != (4,):
            raise document.error(where, f"holds {j.dtype} elements of shape {j.shape[1:]}, not unsigned VEC4")
        if len(j) != count:
            raise document.error(where, f"has {len(j)} elements, but POSITION has {count}")
        w = _attribute(document, attributes, f"WEIGHTS_{k}", here, (4,), count)  # normalized integers read as floats
        joints.append(j)
        weights.append(w)
    return np.concatenate(joints, axis=1), np.concatenate(weights, axis=1)


def _weights(document: GltfDocument, joints: np.ndarray, weights: np.ndarray, here: str) -> SkinWeights:
    try:
        return SkinWeights.of(joints, weights, "vertex weights")
    except ValueError as exc:
        raise document.error(f"{here}.attributes.WEIGHTS_0", str(exc).removeprefix("vertex weights: ")) from None


def _attribute(
    document: GltfDocument, attributes: dict[str, Any], name: str, here: str, shape: tuple[int, ...], count: int = 0,
    inside: str = "attributes",
) -> np.ndarray:  # fmt: skip
    """Attribute `name` of `attributes` (the primitive's `inside` object: its attributes, or a
    morph target) as floats of `shape`, `count` of them when given."""
    where = f"{here}.{inside}.{name}" if inside else f"{here}.{name}"
    values = document.accessor(document.number(attributes, name, f"{here}.{inside}" if inside else here), where)
    if values.shape[1:] != shape or values.dtype.kind != "f":
        raise document.error(where, f"holds {values.dtype} elements of shape {values.shape[1:]}, not float {shape}")
    if count and len(values) != count:
        raise document.error(where, f"has {len(values)} elements, but POSITION has {count}")
    return values


def _triangles(indices: np.ndarray, mode: int) -> np.ndarray:
    """(n, 3) triangles from a list, strip or fan, in the winding the specification gives."""
    if mode == TRIANGLES:
        return indices[: len(indices) - len(indices) % 3].reshape(-1, 3)
    count = max(len(indices) - 2, 0)
    k = np.arange(count)
    if mode == STRIP:  # odd triangles swap their first two vertices to keep the winding
        first = np.where(k % 2 == 0, k, k + 1)
        second = np.where(k % 2 == 0, k + 1, k)
        return np.stack([indices[first], indices[second], indices[k + 2]], axis=1)
    return np.stack([np.full(count, indices[0]), indices[k + 1], indices[k + 2]], axis=1)


def _face_normals(triangles: np.ndarray) -> np.ndarray:
    cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    length = np.linalg.norm(cross, axis=1, keepdims=True)
    return np.where(length > 0.0, cross / np.maximum(length, 1e-30), (0.0, 0.0, 1.0))


class GltfMaterials:
    """The file's materials added to `registry` when first used (handles by material index;
    None: the primitive names none, the caller's default)."""

    def __init__(self, document: GltfDocument, registry: Materials) -> None:
        self.document, self.registry = document, registry
        self.handles: dict[int, int] = {}
        self.images: dict[tuple[Any, bool], int] = {}

    def handle(self, index: int | None, where: str) -> int | None:
        if index is None:
            return None
        if index not in self.handles:
            self.handles[index] = self.registry.add(self._material(index, where))
        return self.handles[index]

    def _material(self, index: int, where: str) -> Material:
        d = self.document
        m = d.item("materials", index, where)
        here = f"materials[{index}]"
        pbr = m.get("pbrMetallicRoughness", {})
        if not isinstance(pbr, dict):
            raise d.error(f"{here}.pbrMetallicRoughness", "is not an object")
        base = np.clip(d.floats(pbr, "baseColorFactor", f"{here}.pbrMetallicRoughness", 4, [1, 1, 1, 1]), 0, 1)
        emissive = np.maximum(d.floats(m, "emissiveFactor", here, 3, [0, 0, 0]), 0.0)
        mode = m.get("alphaMode", "OPAQUE")
        if mode not in ("OPAQUE", "MASK", "BLEND"):
            raise d.error(f"{here}.alphaMode", f"is {mode!r}, not OPAQUE, MASK or BLEND")
        fields: dict[str, Any] = {}
        for slot, (field, color) in GLTF_TEXTURES.items():
            info = pbr.get(slot, m.get(slot))
            if isinstance(info, dict):
                fields[field] = self._texture(info, color, f"{here}.{slot}")
        normal = m.get("normalTexture")
        scale = float(normal.get("scale", 1.0)) if isinstance(normal, dict) else 1.0
        return Material(
            str(m.get("name", f"material{index}")),
            "cook_torrance",
            (float(base[0]), float(base[1]), float(base[2]), float(base[3])),
            metallic=float(np.clip(pbr.get("metallicFactor", 1.0), 0.0, 1.0)),
            roughness=float(np.clip(pbr.get("roughnessFactor", 1.0), 0.0, 1.0)),
            emissive=(float(emissive[0]), float(emissive[1]), float(emissive[2])),
            alpha_mode={"MASK": "mask", "BLEND": "blend"}.get(mode, "opaque"),
            alpha_cutoff=float(np.clip(m.get("alphaCutoff", 0.5), 0.0, 1.0)),
            double_sided=bool(m.get("doubleSided", False)),
            normal_scale=scale if np.isfinite(scale) else 1.0,
            **fields,
        )

    def _texture(self, info: dict[str, Any], color: bool, where: str) -> int:
        d = self.document
        textures = self.registry.textures
        texture = d.item("textures", info.get("index"), f"{where}.index")
        source = texture.get("source")
        key = (source, color)
        if key not in self.images:
            image = d.item("images", source, f"{where} (its texture's source)")
            try:
                if "bufferView" in image:
                    data, offset, length, _ = d.view(d.number(image, "bufferView", where), f"{where}.bufferView")
                    pixels = _decode(data[offset : offset + length])
                    handle = textures.add(Texture(f"{d.file.stem}:image{source}", pixels, color))
                elif isinstance(image.get("uri"), str) and image["uri"].startswith("data:"):
                    pixels = _decode(data_uri(d, image["uri"], f"images[{source}].uri"))
                    handle = textures.add(Texture(f"{d.file.stem}:image{source}", pixels, color))
                else:
                    handle = textures.load(d.file.parent / str(image.get("uri")), color=color, named_by=str(d.file))
            except (ImageError, ValueError, OSError) as exc:
                log.warning("%s: images[%s] cannot be read (%s); drawn with the fallback texture", d.file, source, exc)
                handle = textures.fallback
            self.images[key] = handle
        return self.images[key]


def _decode(data: bytes) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        return pixels_of(Image.open(io.BytesIO(data)))
    except (UnidentifiedImageError, OSError) as exc:
        raise ImageError(str(exc)) from None
