"""A glTF 2.0 file as its JSON and its binary buffers (a .gltf with data URIs or .bin files beside
it, or a .glb), and its accessors decoded into NumPy arrays (accessors.py).

Everything the scene, skins and clips read goes through here, so a broken file fails here with one
GltfError naming the file and the field ("model.gltf: accessors[3].bufferView: ...") before any
entity or GPU object is made.
"""

from __future__ import annotations

import base64
import binascii
import os
import struct
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from ....errors import UsageError
from ....user_files import MODEL, read_user_file
from ....user_json import parse_json

__all__ = ["GltfDocument", "GltfError"]

GLB_MAGIC, GLB_JSON, GLB_BIN = 0x46546C67, 0x4E4F534A, 0x004E4942  # "glTF", "JSON", "BIN\0"


class GltfError(UsageError):
    """A glTF file that breaks the specification, or that the engine cannot use: one line naming
    the file and the field."""


class GltfDocument:
    """The file's JSON (`json`) and its buffers, read when first asked for."""

    def __init__(self, file: Path, document: dict[str, Any], glb_bin: bytes | None) -> None:
        self.file, self.json, self._glb_bin = file, document, glb_bin
        self._buffers: dict[int, bytes] = {}
        self._accessors: dict[int, np.ndarray] = {}

    @classmethod
    def read(cls, path: str | os.PathLike[str]) -> GltfDocument:
        file = Path(path)
        try:
            data = read_user_file(file, MODEL)
        except OSError as exc:
            raise GltfError(f"{file}: cannot be read ({exc.strerror or exc})") from None
        glb_bin = None
        if data[:4] == b"glTF":
            text, glb_bin = _glb_chunks(file, data)
        else:
            text = data
        try:
            document = parse_json(text)
        except ValueError as exc:
            raise GltfError(f"{file}: is not glTF JSON ({exc})") from None
        if not isinstance(document, dict):
            raise GltfError(f"{file}: is not glTF JSON (its top level is not an object)")
        version = document.get("asset", {}).get("version") if isinstance(document.get("asset"), dict) else None
        if not isinstance(version, str) or not version.startswith("2."):
            raise GltfError(f"{file}: asset.version is {version!r}; glTF 2.x is read")
        return cls(file, document, glb_bin)

    # ------------------------------------------------------------------ the JSON
    def error(self, where: str, what: str) -> GltfError:
        return GltfError(f"{self.file}: {where}: {what}")

    def items(self, name: str) -> list[Any]:
        """The top-level array `name` (an empty one when absent)."""
        found = self.json.get(name, [])
        if not isinstance(found, list):
            raise self.error(name, "is not an array")
        return found

    def item(self, name: str, index: Any, where: str) -> dict[str, Any]:
        """`name[index]`, named by `where` (the field that refers to it) when it does not exist."""
        found = self.items(name)
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(found):
            raise self.error(where, f"is {index!r}, not one of the file's {len(found)} {name}")
        entry = found[index]
        if not isinstance(entry, dict):
            raise self.error(f"{name}[{index}]", "is not an object")
        return entry

    def number(self, entry: dict[str, Any], key: str, where: str, default: Any = None, minimum: int = 0) -> int:
        """An integer field of `entry` (`default` when absent and one is given)."""
        value = entry.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(f"{where}.{key}", f"is {value!r}, not an integer")
        if value < minimum:
            raise self.error(f"{where}.{key}", f"is {value}, below {minimum}")
        return value

    def floats(self, entry: dict[str, Any], key: str, where: str, count: int, default: Any) -> np.ndarray:
        """A fixed-length array of finite numbers (`default` when absent)."""
        value = entry.get(key, default)
        try:
            out = np.asarray(value, np.float64).reshape(-1)
        except (TypeError, ValueError):
            out = np.empty(0)
        if out.shape != (count,) or not np.isfinite(out).all():
            raise self.error(f"{where}.{key}", f"is {value!r}, not {count} finite numbers")
        return out

    # -------------------------------------------------------------- the buffers
    def buffer(self, index: int, where: str) -> bytes:
        if index not in self._buffers:
            entry = self.item("buffers", index, where)
            here = f"buffers[{index}]"
            length = self.number(entry, "byteLength", here, minimum=1)
            uri = entry.get("uri")
            if uri is None:
                if self._glb_bin is None or index != 0:
                    raise self.error(here, "has no uri and is not the GLB's binary chunk")
                data = self._glb_bin
            elif not isinstance(uri, str):
                raise self.error(f"{here}.uri", f"is {uri!r}, not a string")
            elif uri.startswith("data:"):
                data = data_uri(self, uri, f"{here}.uri")
            else:
                data = self._external(uri, f"{here}.uri")
            if len(data) < length:
                raise self.error(f"{here}.byteLength", f"is {length}, but the data holds {len(data)} bytes")
            self._buffers[index] = data[:length]
        return self._buffers[index]

    def _external(self, uri: str, where: str) -> bytes:
        path = self.file.parent / unquote(uri)
        try:
            return read_user_file(path, MODEL, named_by=str(self.file))
        except OSError as exc:
            raise self.error(where, f"{path} cannot be read ({exc.strerror or exc})") from None

    def view(self, index: int, where: str) -> tuple[bytes, int, int, int | None]:
        """A bufferView: its buffer's bytes, its offset and length in them, its byteStride (None: tight)."""
        entry = self.item("bufferViews", index, where)
        here = f"bufferViews[{index}]"
        data = self.buffer(self.number(entry, "buffer", here), f"{here}.buffer")
        offset = self.number(entry, "byteOffset", here, default=0)
        length = self.number(entry, "byteLength", here, minimum=1)
        if offset + length > len(data):
            raise self.error(here, f"bytes {offset}..{offset + length} run past its buffer's {len(data)}")
        stride = entry.get("byteStride")
        if stride is not None:
            stride = self.number(entry, "byteStride", here, minimum=4)
            if stride > 252 or stride % 4:
                raise self.error(f"{here}.byteStride", f"is {stride}; it must be a multiple of 4 from 4 to 252")
        return data, offset, length, stride

    def accessor(self, index: int, where: str) -> np.ndarray:
        """Accessor `index` decoded (accessors.py), kept: (count, ...) in the element's shape;
        floats and normalized integers as float32, other integers in their own type."""
        if index not in self._accessors:
            from .accessors import decode

            self.item("accessors", index, where)
            self._accessors[index] = decode(self, index)
        return self._accessors[index]


def _glb_chunks(file: Path, data: bytes) -> tuple[bytes, bytes | None]:
    """A GLB's JSON chunk and its binary chunk (None without one)."""
    if len(data) < 20:
        raise GltfError(f"{file}: is a GLB of {len(data)} bytes, shorter than its header")
    _, version, length = struct.unpack_from("<III", data, 0)
    if version != 2:
        raise GltfError(f"{file}: is a GLB of version {version}; version 2 is read")
    if length > len(data):
        raise GltfError(f"{file}: its GLB header says {length} bytes, but the file has {len(data)}")
    chunks: list[tuple[int, bytes]] = []
    at = 12
    while at + 8 <= length:
        size, kind = struct.unpack_from("<II", data, at)
        if at + 8 + size > length:
            raise GltfError(f"{file}: GLB chunk {len(chunks)} runs past the file's end")
        chunks.append((kind, data[at + 8 : at + 8 + size]))
        at += 8 + size + (-size % 4)
    if not chunks or chunks[0][0] != GLB_JSON:
        raise GltfError(f"{file}: the GLB's first chunk is not its JSON")
    binary = chunks[1][1] if len(chunks) > 1 and chunks[1][0] == GLB_BIN else None
    return chunks[0][1], binary


def data_uri(document: GltfDocument, uri: str, where: str) -> bytes:
    head, _, body = uri.partition(",")
    if not head.endswith(";base64"):
        raise document.error(where, f"is a data URI that is not base64 ({head[:40]!r})")
    try:
        return base64.b64decode(body, validate=True)
    except (binascii.Error, ValueError) as exc:
        raise document.error(where, f"is a data URI whose base64 is broken ({exc})") from None
