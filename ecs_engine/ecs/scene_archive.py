"""Reading a scene file's zip archive (scene_file.py is the format): every member is checked before
anything the size of its data is allocated: names safe and used once, sizes within the archive,
.npy headers as expected, and a resource's arrays as its codec allows (`check_array`), so a
small file cannot ask for gigabytes. The header's JSON is read with user_json's bounds.
"""

from __future__ import annotations

import math
import re
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from ..user_json import parse_json
from .errors import EcsError
from .schema import Component

FORMAT = "ecs_engine.scene"
READS = (1, 2)  # format versions this engine loads
HEADER_LIMIT = 16 << 20  # bytes of JSON header a scene may have
DEFLATE_RATIO = 1100  # deflate never expands more than ~1032:1; a member claiming more is a bomb
MEMBER = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*(/[A-Za-z0-9_][A-Za-z0-9_.-]*)*\Z")  # no "..", "/x", "C:"
ARRAY_KEY = re.compile(r"[A-Za-z0-9_]{1,64}\Z")
_T = TypeVar("_T")


class SceneFileError(EcsError, ValueError):
    """A scene file that cannot be saved or loaded; the world (and any old file) is unchanged."""


@dataclass(frozen=True)
class SavedResource:
    """What a codec saves: a JSON-able document and named arrays (keys [A-Za-z0-9_], no objects)."""

    doc: Any
    arrays: Mapping[str, np.ndarray] = field(default_factory=dict)


@dataclass
class SavedTable:
    types: list[type[Component]]
    ids: np.ndarray
    values: dict[type[Component], dict[str, np.ndarray]]


def fail(path: Path, why: str) -> SceneFileError:
    return SceneFileError(f"scene file {path}: {why}")


def check(ok: bool, path: Path, why: str) -> None:
    if not ok:
        raise fail(path, why)


def need(value: _T | None, path: Path, why: str) -> _T:
    if value is None:
        raise fail(path, why)
    return value


def is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


class SceneArchive:
    """Reads members of one archive, each checked before anything the size of its data is
    allocated: names safe and used once, sizes within the archive, .npy headers as expected."""

    def __init__(self, archive: zipfile.ZipFile, path: Path, size: int) -> None:
        self.archive, self.path = archive, path
        infos = archive.infolist()
        names = [i.filename for i in infos]
        check(len(names) == len(set(names)), path, "it names a member twice")
        for info in infos:
            check(bool(MEMBER.match(info.filename)), path, f"member name {info.filename[:80]!r} leaves the archive")
            check(not info.flag_bits & 1, path, f"member {info.filename} is encrypted")
            check(info.compress_type in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED), path, "an unknown compression")
        check(sum(i.compress_size for i in infos) <= size, path, "its members overlap or claim more than it holds")
        for info in infos:
            stored = info.compress_type == zipfile.ZIP_STORED
            limit = info.compress_size if stored else DEFLATE_RATIO * info.compress_size + 1024
            check(info.file_size <= limit, path, f"member {info.filename} claims more than it holds")
        self.infos = {i.filename: i for i in infos}
        self.used: set[str] = set()

    def info(self, member: Any) -> zipfile.ZipInfo:
        check(isinstance(member, str) and member in self.infos, self.path, f"member {str(member)[:80]} is missing")
        check(member not in self.used, self.path, f"member {member} is named twice in the header")
        self.used.add(member)
        return self.infos[member]

    def header(self) -> dict[str, Any]:
        info = self.info("header.json")
        check(info.file_size <= HEADER_LIMIT, self.path, f"header.json is over {HEADER_LIMIT} bytes")
        try:
            header = parse_json(self.archive.read(info))
        except ValueError as exc:
            raise fail(self.path, f"header.json: {exc}") from None
        check(isinstance(header, dict) and header.get("format") == FORMAT, self.path, "not a scene file")
        version = header.get("version")
        ok = is_count(version) and version in READS  # true == 1 and 2.0 == 2 in Python: not versions
        check(ok, self.path, f"format version {repr(version)[:40]}; this engine reads versions {READS}")
        header.setdefault("resources", [])
        ok = isinstance(header.get("tables"), list) and isinstance(header["resources"], list)
        check(ok and is_count(header.get("entities")), self.path, "header.json lacks its entities, tables or resources")
        return header

    def array(
        self,
        member: Any,
        dtype: np.dtype | None,
        shape: tuple[int, ...] | None,
        allow: Callable[[np.dtype, tuple[int, ...]], None] | None = None,
    ) -> np.ndarray:
        """The member's array; its dtype and shape must be these (None: any, no objects), and
        `allow` (a ValueError: why not) is asked before its data is read."""
        info, path = self.info(member), self.path
        with self.archive.open(info) as data:
            try:
                version = np.lib.format.read_magic(data)
                check(version in ((1, 0), (2, 0)), path, f"member {member} is .npy version {version}")
                read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
                got_shape, fortran, got = read(data)
            except (ValueError, OSError, EOFError, SyntaxError) as exc:
                raise fail(path, f"member {member} is not a NumPy array ({exc})") from None
            check(not got.hasobject, path, f"member {member} holds Python objects")
            check(got.itemsize > 0 and min(got_shape, default=0) >= 0, path, f"member {member} has no sizes")
            expect = f"{dtype} {shape}" if dtype is not None else "no objects"
            ok = (dtype is None or got == dtype) and (shape is None or tuple(got_shape) == shape)
            check(ok, path, f"member {member} is {got} {tuple(got_shape)}, expected {expect}")
            if allow is not None:
                try:
                    allow(got, tuple(got_shape))
                except ValueError as exc:
                    raise fail(path, f"member {member}: {exc}") from None
            nbytes = math.prod(got_shape) * got.itemsize
            check(nbytes == info.file_size - data.tell(), path, f"member {member} does not hold {got_shape} of {got}")
            raw = data.read(nbytes)
            check(len(raw) == nbytes and not data.read(1), path, f"member {member} is truncated")
        return np.frombuffer(raw, got).reshape(got_shape, order="F" if fortran else "C")

    def table(self, k: int, spec: Any, known: Mapping[str, type[Component] | None]) -> SavedTable:
        path = self.path
        ok = isinstance(spec, dict) and is_count(spec.get("rows")) and isinstance(spec.get("components"), list)
        check(ok and isinstance(spec.get("columns"), list), path, f"table {k} lacks rows, components or columns")
        rows, types = spec["rows"], []
        for name in spec["components"]:
            ct = known.get(name) if isinstance(name, str) else None
            if ct is None:
                why = "two classes have that name" if name in known else "import the module that defines it first"
                raise fail(path, f"unknown component {str(name)[:200]!r} ({why})")
            check(ct not in types, path, f"table {k} names {name} twice")
            types.append(ct)
        ids = self.array(spec.get("ids"), np.dtype(np.int64), (rows,))
        values: dict[type[Component], dict[str, np.ndarray]] = {ct: {} for ct in types}
        for column in spec["columns"]:
            ok = isinstance(column, dict) and isinstance(column.get("component"), str)
            ct = known.get(column["component"]) if ok else None
            ct = need(ct if ct in values else None, path, f"table {k}: a column of no component of it: {column}"[:300])
            field = column.get("field")
            f = need(ct.__fields__.get(field) if isinstance(field, str) else None, path, f"no field {field}"[:200])
            check(f.name not in values[ct], path, f"table {k}: {f.qualname} is given twice")
            said = (column.get("dtype"), column.get("shape"))
            check(said == (f.dtype.str, list(f.shape)), path, f"table {k}: {f.qualname} is {said}, the field is not")
            values[ct][f.name] = self.array(column.get("member"), f.dtype, (rows, *f.shape))
        return SavedTable(types, ids, values)  # fields not saved get their defaults (a field added since)

    def resource(self, spec: Any, codecs: Mapping[str, Any]) -> tuple[str, str, SavedResource]:
        """A resource's document and arrays; each array's dtype and shape are first shown to its
        codec's `check_array(key, dtype, shape)` when it has one (a ValueError: refused)."""
        ok = isinstance(spec, dict) and isinstance(spec.get("name"), str) and isinstance(spec.get("arrays"), dict)
        check(ok, self.path, f"a resource lacks its name or arrays: {str(spec)[:200]}")
        check_array = getattr(codecs.get(spec["name"]), "check_array", None)
        arrays = {}
        for key, said in spec["arrays"].items():
            check(isinstance(said, dict) and bool(ARRAY_KEY.match(key)), self.path, f"resource array {key[:80]!r}")
            allow = None if check_array is None else lambda dtype, shape, key=key: check_array(key, dtype, shape)
            array = self.array(said.get("member"), None, None, allow)
            same = [array.dtype.str, list(array.shape)] == [said.get("dtype"), said.get("shape")]
            check(same, self.path, f"resource array {key} is not the dtype and shape its header says")
            arrays[key] = array
        return spec["name"], str(spec.get("module", "?")), SavedResource(spec.get("doc"), arrays)

    def all_used(self) -> None:
        extra = sorted(set(self.infos) - self.used)
        check(not extra, self.path, f"member {extra[0] if extra else ''} is not in the header")
