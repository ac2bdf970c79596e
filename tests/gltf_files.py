"""glTF 2.0 files built in the tests, in plain Python and NumPy (no exporter, whose choices would hide
the corners): the JSON and one binary buffer laid out exactly as the Khronos specification says, so
tests can reach what exporters rarely write (strides with garbage between elements, normalized
integers, sparse sections over a view or over zeros, matrix columns padded to 4 bytes) and break
the rest by editing `json` or `data` before writing."""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

BYTE, UNSIGNED_BYTE, SHORT, UNSIGNED_SHORT, UNSIGNED_INT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
DTYPES = {BYTE: "<i1", UNSIGNED_BYTE: "<u1", SHORT: "<i2", UNSIGNED_SHORT: "<u2", UNSIGNED_INT: "<u4", FLOAT: "<f4"}
SHAPES = {"SCALAR": (), "VEC2": (2,), "VEC3": (3,), "VEC4": (4,), "MAT2": (2, 2), "MAT3": (3, 3), "MAT4": (4, 4)}
TYPES = {shape: name for name, shape in SHAPES.items()}
GARBAGE = 0xAB  # fills stride gaps, matrix column padding and accessor offsets: a reader that reads them fails
LIGHTS = "KHR_lights_punctual"


def _encode(values: Any, component: int, normalized: bool) -> np.ndarray:
    """Values as stored: floats given for a normalized integer type are scaled by the spec's
    formulas (unsigned f * (2^n - 1), signed f * (2^(n-1) - 1), rounded); integers stay as given."""
    dtype = np.dtype(DTYPES[component])
    values = np.asarray(values)
    if normalized and values.dtype.kind == "f":
        bits = 8 * dtype.itemsize
        top = 2**bits - 1 if dtype.kind == "u" else 2 ** (bits - 1) - 1
        return np.round(values.astype(np.float64) * top).astype(dtype)
    return values.astype(dtype)


def _rows(encoded: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Each element's bytes as glTF lays it out, (count, element size) uint8: matrices column by
    column (numpy's m[row][col] transposed), each column padded to 4 bytes (spec 3.6.2.4)."""
    n = len(encoded)
    if len(shape) == 2:
        columns = np.ascontiguousarray(encoded.transpose(0, 2, 1)).view(np.uint8).reshape(n, shape[1], -1)
        pad = np.full((n, shape[1], -columns.shape[2] % 4), GARBAGE, np.uint8)
        return np.concatenate([columns, pad], axis=2).reshape(n, -1)
    return np.ascontiguousarray(encoded).view(np.uint8).reshape(n, -1)


def _some(**fields: Any) -> dict[str, Any]:
    """The fields given (not None): optional glTF properties are left out, not written as defaults."""
    return {key: value for key, value in fields.items() if value is not None}


def _floats(values: Any) -> list[float] | None:
    return None if values is None else [float(v) for v in np.asarray(values, np.float64).reshape(-1)]


def _index(value: Any) -> bool:
    """An int where an array is expected names an accessor already made (a custom one: strided, normalized)."""
    return isinstance(value, int | np.integer)


class GltfBuilder:
    """One glTF document and its one buffer (buffers[0]); each method appends an object and returns its index."""

    def __init__(self) -> None:
        self.json: dict[str, Any] = {"asset": {"version": "2.0", "generator": "ecs_engine tests"}}
        self.data = bytearray()  # buffers[0]'s bytes; tests may corrupt them

    def _add(self, name: str, entry: dict[str, Any]) -> int:
        self.json.setdefault(name, []).append(entry)
        return len(self.json[name]) - 1

    def _view(self, raw: bytes, stride: int | None = None, target: int | None = None) -> int:
        """A bufferView over `raw`, starting on a 4-byte boundary (covers every component size and
        the vertex attributes' 4-byte rule); the bytes skipped are zeros."""
        self.data += b"\0" * (-len(self.data) % 4)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw)}
        self.data += raw
        return self._add("bufferViews", {**view, **_some(byteStride=stride, target=target)})

    def accessor(
        self, values: Any, component_type: int | None = None, *, type: str | None = None, count: int | None = None,
        normalized: bool = False, stride: int | None = None, target: int | None = None,
        sparse: dict[str, Any] | None = None, min_max: bool = False, byte_offset: int = 0, name: str | None = None,
    ) -> int:  # fmt: skip
        """An accessor over `values` (shape (n,), (n, k) or (n, k, k) unless `type` says; None: no
        bufferView, zeros, with `count` and `type`). `stride`: the view's byteStride, gaps of garbage
        (vertex attributes whose element is not a multiple of 4 bytes get one anyway, as the spec
        requires). `byte_offset`: the accessor's byteOffset, garbage before it. `sparse`: {"indices",
        "values", "index_component_type"}, both in one view (values at a nonzero byteOffset)."""
        if values is None:
            if count is None or type is None:
                raise ValueError("an accessor without values needs count= and type=")
            shape, component = SHAPES[type], component_type or FLOAT
            base = np.zeros((count, *shape), DTYPES[component])
        else:
            values = np.asarray(values)
            if type is not None:
                values = values.reshape(-1, *SHAPES[type])
            shape = values.shape[1:]
            if shape not in TYPES:
                raise ValueError(f"no accessor type has elements of shape {shape}")
            type = TYPES[shape]
            component = component_type or (FLOAT if values.dtype.kind == "f" else UNSIGNED_INT)
            base = _encode(values, component, normalized)
            count = len(base)
        if normalized and component in (FLOAT, UNSIGNED_INT):
            raise ValueError("normalized needs a byte or short component type")
        entry: dict[str, Any] = {"componentType": component, "count": count, "type": type}
        if values is not None:
            rows, item = _rows(base, shape), base.dtype.itemsize
            size = rows.shape[1]
            if stride is None and target == ARRAY_BUFFER and size % 4:
                stride = size + -size % 4
            raw = rows.tobytes()
            if stride is not None:
                vertex = 4 if target == ARRAY_BUFFER else 1
                if not size <= stride <= 252 or stride < 4 or stride % item or stride % vertex:
                    raise ValueError(f"byteStride {stride} does not fit elements of {size} bytes")
                if target == ELEMENT_ARRAY_BUFFER:
                    raise ValueError("index views must not have a byteStride")
                spaced = np.full((count, stride), GARBAGE, np.uint8)
                spaced[:, :size] = rows
                raw = spaced.tobytes()[: stride * (count - 1) + size]  # no gap after the last element
            if byte_offset % item or (target == ARRAY_BUFFER and byte_offset % 4):
                raise ValueError(f"byteOffset {byte_offset} is not aligned")
            entry["bufferView"] = self._view(bytes([GARBAGE]) * byte_offset + raw, stride, target)
            if byte_offset:
                entry["byteOffset"] = byte_offset
        if normalized:
            entry["normalized"] = True
        if sparse is not None:
            index_type = sparse.get("index_component_type", UNSIGNED_INT)
            at = np.asarray(sparse["indices"]).astype(DTYPES[index_type]).reshape(-1)
            new = _encode(np.asarray(sparse["values"]).reshape(len(at), *shape), component, normalized)
            head = at.tobytes() + b"\0" * (-at.nbytes % 4)
            view = self._view(head + _rows(new, shape).tobytes())
            indices = {"bufferView": view, "byteOffset": 0, "componentType": index_type}
            changed = {"bufferView": view, "byteOffset": len(head)}
            entry["sparse"] = {"count": len(at), "indices": indices, "values": changed}
            base = base.copy()
            base[at] = new
        if min_max:  # of the stored values (raw integers when normalized), after the sparse substitution, by columns
            flat = (base.transpose(0, 2, 1) if len(shape) == 2 else base).reshape(count, -1)
            entry["min"], entry["max"] = flat.min(axis=0).tolist(), flat.max(axis=0).tolist()
        return self._add("accessors", {**entry, **_some(name=name)})

    def node(
        self, name: str | None = None, *, translation: Any = None, rotation: Any = None, scale: Any = None,
        matrix: Any = None, mesh: int | None = None, camera: int | None = None, light: int | None = None,
        skin: int | None = None, children: list[int] | None = None,
    ) -> int:  # fmt: skip
        """A node; `rotation` is (x, y, z, w), `matrix` is m[row][col] (written by columns)."""
        by_columns = None if matrix is None else np.asarray(matrix, np.float64).reshape(4, 4).T
        entry = _some(name=name, translation=_floats(translation), rotation=_floats(rotation), scale=_floats(scale),
                      matrix=_floats(by_columns), mesh=mesh, camera=camera, skin=skin, children=children)  # fmt: skip
        if light is not None:
            entry["extensions"] = {LIGHTS: {"light": light}}
        return self._add("nodes", entry)

    def mesh(self, primitives: list[dict[str, Any]], name: str | None = None, weights: Any = None) -> int:
        return self._add("meshes", {"primitives": primitives, **_some(name=name, weights=_floats(weights))})

    def _attribute(self, value: Any, dtype: Any = None, component: int | None = None, min_max: bool = False) -> int:
        if _index(value):
            return int(value)
        return self.accessor(np.asarray(value, dtype), component, target=ARRAY_BUFFER, min_max=min_max)

    def primitive(
        self, positions: Any, indices: Any = None, *, normals: Any = None, uv: Any = None, material: int | None = None,
        mode: int | None = None, joints: Any = None, weights: Any = None, targets: list[dict[str, Any]] | None = None,
        **more_attributes: Any,
    ) -> dict[str, Any]:  # fmt: skip
        """A primitive's dict for mesh(), its accessors made (any argument may instead be an accessor's
        index). Indices take the smallest unsigned type that keeps clear of the restart value."""
        attributes = {"POSITION": self._attribute(positions, np.float32, min_max=True)}
        floats = {"NORMAL": normals, "TEXCOORD_0": uv, "WEIGHTS_0": weights}
        for key, value in {**floats, "JOINTS_0": joints, **more_attributes}.items():
            if value is not None:  # joints: UNSIGNED_BYTE or UNSIGNED_SHORT, as the spec allows
                joint = key == "JOINTS_0" and (UNSIGNED_BYTE if np.max(value) < 256 else UNSIGNED_SHORT)
                attributes[key] = self._attribute(value, np.float32 if key in floats else None, joint or None)
        if indices is not None and not _index(indices):
            top = int(np.max(indices))
            kind = UNSIGNED_BYTE if top < 255 else UNSIGNED_SHORT if top < 65535 else UNSIGNED_INT
            indices = self.accessor(np.asarray(indices).reshape(-1), kind, target=ELEMENT_ARRAY_BUFFER)
        out: dict[str, Any] = {"attributes": attributes, **_some(indices=indices, material=material, mode=mode)}
        if targets is not None:
            out["targets"] = [
                {k: self._attribute(v, np.float32, min_max=k == "POSITION") for k, v in target.items()}
                for target in targets
            ]
        return out

    def material(
        self, name: str | None = None, *, base_color: Any = (1.0, 1.0, 1.0, 1.0), metallic: float = 1.0,
        roughness: float = 1.0, emissive: Any = None, alpha_mode: str | None = None,
        alpha_cutoff: float | None = None, double_sided: bool | None = None,
    ) -> int:  # fmt: skip
        pbr = {"baseColorFactor": _floats(base_color), "metallicFactor": metallic, "roughnessFactor": roughness}
        entry = _some(name=name, pbrMetallicRoughness=pbr, emissiveFactor=_floats(emissive), alphaMode=alpha_mode,
                      alphaCutoff=alpha_cutoff, doubleSided=double_sided)  # fmt: skip
        return self._add("materials", entry)

    def camera_perspective(
        self, yfov: float, znear: float, zfar: float | None = None, aspect: float | None = None
    ) -> int:
        """`zfar` None: an infinite projection; `aspect` None: the viewport's."""
        perspective = _some(yfov=yfov, znear=znear, zfar=zfar, aspectRatio=aspect)
        return self._add("cameras", {"type": "perspective", "perspective": perspective})

    def camera_orthographic(self, xmag: float, ymag: float, znear: float, zfar: float) -> int:
        ortho = {"xmag": xmag, "ymag": ymag, "znear": znear, "zfar": zfar}
        return self._add("cameras", {"type": "orthographic", "orthographic": ortho})

    def light(
        self, type: str, *, color: Any = None, intensity: float | None = None, range: float | None = None,
        inner: float | None = None, outer: float | None = None, name: str | None = None,
    ) -> int:  # fmt: skip
        """A KHR_lights_punctual light (directional, point, spot); a spot always has its required
        "spot" object, with only the cone angles given (the extension's defaults otherwise)."""
        light = _some(name=name, type=type, color=_floats(color), intensity=intensity, range=range)
        if type == "spot":
            light["spot"] = _some(innerConeAngle=inner, outerConeAngle=outer)
        if LIGHTS not in (used := self.json.setdefault("extensionsUsed", [])):
            used.append(LIGHTS)
        lights = self.json.setdefault("extensions", {}).setdefault(LIGHTS, {}).setdefault("lights", [])
        lights.append(light)
        return len(lights) - 1

    def skin(self, joints: list[int], inverse_bind_matrices: Any = None, skeleton: int | None = None) -> int:
        """`inverse_bind_matrices`: (n, 4, 4) m[row][col] (a MAT4 accessor), or an accessor's index."""
        matrices = inverse_bind_matrices
        if matrices is not None and not _index(matrices):
            matrices = self.accessor(np.asarray(matrices, np.float32).reshape(-1, 4, 4))
        return self._add("skins", {"joints": joints, **_some(inverseBindMatrices=matrices, skeleton=skeleton)})

    def animation(self, channels: list[tuple[int, str, Any, Any, str]], name: str | None = None) -> int:
        """Each channel (node, path, times, values, interpolation) gets its own sampler; input FLOAT
        with min/max, output FLOAT VEC3 (VEC4 for rotation, SCALAR for weights), keys x 3 for
        CUBICSPLINE (in-tangent, value, out-tangent). Times or values may be an accessor's index;
        interpolation None leaves it out (LINEAR by default), node None leaves the node out."""
        samplers: list[dict[str, Any]] = []
        targets: list[dict[str, Any]] = []
        for node, path, times, values, interpolation in channels:
            if not _index(times):
                times = self.accessor(np.asarray(times, np.float32).reshape(-1), min_max=True)
            if not _index(values):
                values = np.asarray(values, np.float32)
                width = {"weights": 1, "rotation": 4}.get(path, 3)
                values = self.accessor(values.reshape(-1) if width == 1 else values.reshape(-1, width))
            samplers.append(_some(input=times, output=values, interpolation=interpolation))
            targets.append({"sampler": len(samplers) - 1, "target": _some(node=node, path=path)})
        return self._add("animations", {"channels": targets, "samplers": samplers, **_some(name=name)})

    def scene(self, nodes: list[int], name: str | None = None, default: bool = True) -> int:
        """A scene of root nodes; `default` makes it the document's "scene"."""
        index = self._add("scenes", {"nodes": nodes, **_some(name=name)})
        if default:
            self.json["scene"] = index
        return index

    def _document(self, uri: str | None) -> str:
        """The JSON with buffers[0] filled in (what a test put in json["buffers"][0] wins), UTF-8 text."""
        document = json.loads(json.dumps(self.json, default=lambda v: np.asarray(v).tolist()))  # numpy ints too
        if self.data or "buffers" in document:
            buffers = document.get("buffers") or [{}]
            buffers[0] = {"byteLength": len(self.data), **_some(uri=uri), **buffers[0]}
            document["buffers"] = buffers
        return json.dumps(document, ensure_ascii=False, allow_nan=False)

    def gltf(self, path: str | Path, embed: bool = True) -> Path:
        """A .gltf; the buffer as a base64 data URI, or (embed False) in `<stem>.bin` beside it,
        named by a relative, percent-encoded URI."""
        path = Path(path)
        uri = None
        if self.data and embed:
            uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.data)).decode("ascii")
        elif self.data:
            (path.parent / f"{path.stem}.bin").write_bytes(bytes(self.data))
            uri = quote(f"{path.stem}.bin")
        path.write_text(self._document(uri), encoding="utf-8")
        return path

    def glb(self, path: str | Path) -> Path:
        """A .glb: header (magic, version 2, length), the JSON chunk padded with spaces, the BIN chunk
        padded with zeros (byteLength stays the unpadded size); no BIN chunk when there is no data."""
        path = Path(path)
        text = self._document(None).encode("utf-8")
        text += b" " * (-len(text) % 4)
        chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
        if self.data:
            binary = bytes(self.data) + b"\0" * (-len(self.data) % 4)
            chunks += struct.pack("<II", len(binary), 0x004E4942) + binary
        path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)
        return path
