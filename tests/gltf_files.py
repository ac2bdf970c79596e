"""glTF 2.0 test files made in the tests (no exporter): a builder that writes the JSON and one
binary buffer by the specification (aligned views, matrix columns padded to 4 bytes, strided
views with garbage between elements, normalized integers, sparse sections), as a .gltf with
the buffer embedded or beside it, or as a .glb."""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path
from typing import Any

import numpy as np

FLOAT, UINT = 5126, 5125
DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
TYPES = {(): "SCALAR", (2,): "VEC2", (3,): "VEC3", (4,): "VEC4", (2, 2): "MAT2", (3, 3): "MAT3", (4, 4): "MAT4"}


class GltfBuilder:
    def __init__(self) -> None:
        self.json: dict[str, Any] = {"asset": {"version": "2.0", "generator": "ecs_engine tests"}}
        self.data = bytearray()

    def _list(self, name: str) -> list[Any]:
        return self.json.setdefault(name, [])

    def _add(self, name: str, entry: dict[str, Any]) -> int:
        items = self._list(name)
        items.append(entry)
        return len(items) - 1

    def _view(self, raw: bytes, align: int, stride: int | None = None, target: int | None = None) -> int:
        self.data += b"\0" * (-len(self.data) % max(align, 4))
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw)}
        if stride is not None:
            view["byteStride"] = stride
        if target is not None:
            view["target"] = target
        self.data += raw
        return self._add("bufferViews", view)

    @staticmethod
    def _encode(values: np.ndarray, component: int, normalized: bool) -> np.ndarray:
        dtype = np.dtype(DTYPES[component])
        if normalized:
            bits = dtype.itemsize * 8
            top = 2**bits - 1 if dtype.kind == "u" else 2 ** (bits - 1) - 1
            return np.round(np.asarray(values, np.float64) * top).astype(dtype)
        return np.asarray(values).astype(dtype)

    @staticmethod
    def _bytes(values: np.ndarray, shape: tuple[int, ...]) -> tuple[bytes, int]:
        """The elements stored as glTF lays them out (matrices by columns, each padded to 4
        bytes), and one element's size."""
        if len(shape) == 2:
            columns = np.ascontiguousarray(values.transpose(0, 2, 1))  # [element, column, row]
            size = columns.shape[2] * values.dtype.itemsize
            pad = -size % 4
            raw = columns.view(np.uint8).reshape(len(values), shape[1], size)
            raw = np.concatenate([raw, np.zeros((len(values), shape[1], pad), np.uint8)], axis=2)
            return raw.tobytes(), (size + pad) * shape[1]
        return np.ascontiguousarray(values).tobytes(), int(np.prod(shape, dtype=int)) * values.dtype.itemsize

    def accessor(
        self,
        values: Any,
        component_type: int | None = None,
        *,
        type: str | None = None,
        count: int | None = None,
        normalized: bool = False,
        stride: int | None = None,
        target: int | None = None,
        sparse: dict[str, Any] | None = None,
        min_max: bool = False,
    ) -> int:
        """An accessor of `values` (None: no buffer view, zeros, with `type` and `count`)."""
        shape: tuple[int, ...]
        if values is None:
            shape = next(k for k, v in TYPES.items() if v == type)
            component = FLOAT if component_type is None else component_type
            entry: dict[str, Any] = {"componentType": component, "count": count, "type": type}
        else:
            values = np.asarray(values)
            shape = values.shape[1:]
            component = component_type or (FLOAT if values.dtype.kind == "f" else UINT)
            encoded = self._encode(values, component, normalized)
            raw, size = self._bytes(encoded, shape)
            if stride is not None:  # elements `stride` bytes apart, 0xAB between them
                rows = np.frombuffer(raw, np.uint8).reshape(len(values), size)
                padded = np.full((len(values), stride), 0xAB, np.uint8)
                padded[:, :size] = rows
                raw = padded.tobytes()
            entry = {"componentType": component, "count": len(values), "type": type or TYPES[shape]}
            entry["bufferView"] = self._view(raw, encoded.dtype.itemsize, stride, target)
            if min_max:
                entry["min"] = np.asarray(values).reshape(len(values), -1).min(axis=0).tolist()
                entry["max"] = np.asarray(values).reshape(len(values), -1).max(axis=0).tolist()
        if normalized:
            entry["normalized"] = True
        if sparse is not None:
            index_type = sparse.get("index_component_type", UINT)
            at = np.asarray(sparse["indices"]).astype(DTYPES[index_type])
            new = self._encode(np.asarray(sparse["values"]), component, normalized)
            raw, _ = self._bytes(new, shape)
            entry["sparse"] = {
                "count": len(at),
                "indices": {"bufferView": self._view(at.tobytes(), at.dtype.itemsize), "componentType": index_type},
                "values": {"bufferView": self._view(raw, new.dtype.itemsize)},
            }
        return self._add("accessors", entry)

    def primitive(
        self, positions: Any, indices: Any = None, *, normals: Any = None, uv: Any = None, material: int | None = None,
        mode: int | None = None, **more: Any,
    ) -> dict[str, Any]:  # fmt: skip
        attributes = {"POSITION": self.accessor(np.asarray(positions, np.float32), target=34962, min_max=True)}
        if normals is not None:
            attributes["NORMAL"] = self.accessor(np.asarray(normals, np.float32), target=34962)
        if uv is not None:
            attributes["TEXCOORD_0"] = self.accessor(np.asarray(uv, np.float32), target=34962)
        for name, value in more.items():
            attributes[name] = self.accessor(value, target=34962)
        out: dict[str, Any] = {"attributes": attributes}
        if indices is not None:
            indices = np.asarray(indices)
            kind = 5121 if indices.max() < 256 else 5123 if indices.max() < 65536 else UINT
            out["indices"] = self.accessor(indices, kind, target=34963)
        if material is not None:
            out["material"] = material
        if mode is not None:
            out["mode"] = mode
        return out

    def mesh(self, primitives: list[dict[str, Any]], name: str | None = None) -> int:
        return self._add("meshes", {"primitives": primitives, **({"name": name} if name else {})})

    def material(
        self, name: str, *, base_color=(1.0, 1.0, 1.0, 1.0), metallic=1.0, roughness=1.0, alpha_mode=None,
        double_sided=None, emissive=None,
    ) -> int:  # fmt: skip
        pbr = {"baseColorFactor": list(base_color), "metallicFactor": metallic, "roughnessFactor": roughness}
        entry: dict[str, Any] = {"name": name, "pbrMetallicRoughness": pbr}
        if alpha_mode is not None:
            entry["alphaMode"] = alpha_mode
        if double_sided is not None:
            entry["doubleSided"] = double_sided
        if emissive is not None:
            entry["emissiveFactor"] = list(emissive)
        return self._add("materials", entry)

    def camera_perspective(
        self, yfov: float, znear: float, zfar: float | None = None, aspect: float | None = None
    ) -> int:
        p: dict[str, Any] = {"yfov": yfov, "znear": znear}
        if zfar is not None:
            p["zfar"] = zfar
        if aspect is not None:
            p["aspectRatio"] = aspect
        return self._add("cameras", {"type": "perspective", "perspective": p})

    def light(self, type: str, *, color=None, intensity=None, range=None, inner=None, outer=None) -> int:
        light: dict[str, Any] = {"type": type}
        for key, value in (("color", color), ("intensity", intensity), ("range", range)):
            if value is not None:
                light[key] = list(value) if key == "color" else value
        if type == "spot":
            light["spot"] = {k: v for k, v in (("innerConeAngle", inner), ("outerConeAngle", outer)) if v is not None}
        self.json.setdefault("extensionsUsed", []).append("KHR_lights_punctual") if "KHR_lights_punctual" not in \
            self.json.get("extensionsUsed", []) else None  # fmt: skip
        lights = self.json.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {}).setdefault("lights", [])
        lights.append(light)
        return len(lights) - 1

    def node(self, name: str | None = None, *, translation=None, rotation=None, scale=None, matrix=None, mesh=None,
             camera=None, light=None, children=None) -> int:  # fmt: skip
        entry: dict[str, Any] = {} if name is None else {"name": name}
        for key, value in (("translation", translation), ("rotation", rotation), ("scale", scale)):
            if value is not None:
                entry[key] = [float(v) for v in value]
        if matrix is not None:
            entry["matrix"] = [float(v) for v in np.asarray(matrix, np.float64).T.reshape(-1)]  # by columns
        for key, value in (("mesh", mesh), ("camera", camera), ("children", children)):
            if value is not None:
                entry[key] = value
        if light is not None:
            entry["extensions"] = {"KHR_lights_punctual": {"light": light}}
        return self._add("nodes", entry)

    def animation(self, channels: list[tuple[int, str, Any, Any, str]], name: str | None = None) -> int:
        """Each channel (node, path, times, values, interpolation): its own sampler, whose output
        is `values` as given (keys x 3 for CUBICSPLINE: in-tangent, value, out-tangent)."""
        samplers, out = [], []
        for node, path, times, values, interpolation in channels:
            values = np.asarray(values, np.float32)
            flat = values.reshape(-1) if path == "weights" else values.reshape(-1, values.shape[-1])
            sampler = {
                "input": self.accessor(np.asarray(times, np.float32), min_max=True),
                "output": self.accessor(flat),
                "interpolation": interpolation,
            }
            samplers.append(sampler)
            out.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path}})
        return self._add("animations", {"samplers": samplers, "channels": out, **({"name": name} if name else {})})

    def scene(self, nodes: list[int]) -> int:
        index = self._add("scenes", {"nodes": nodes})
        self.json.setdefault("scene", index)
        return index

    def _document(self, uri: str | None) -> dict[str, Any]:
        document = json.loads(json.dumps(self.json))
        buffer: dict[str, Any] = {"byteLength": len(self.data)}
        if uri is not None:
            buffer["uri"] = uri
        document["buffers"] = [buffer]
        return document

    def gltf(self, path: Path, embed: bool = True) -> Path:
        path = Path(path)
        if embed:
            uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.data)).decode()
        else:
            uri = path.stem + ".bin"
            (path.parent / uri).write_bytes(bytes(self.data))
        path.write_text(json.dumps(self._document(uri)))
        return path

    def glb(self, path: Path) -> Path:
        path = Path(path)
        text = json.dumps(self._document(None)).encode()
        text += b" " * (-len(text) % 4)
        binary = bytes(self.data) + b"\0" * (-len(self.data) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(binary), 0x004E4942) + binary
        path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
        return path
