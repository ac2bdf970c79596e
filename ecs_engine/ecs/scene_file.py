"""Saved scenes: a world's entities as NumPy columns in one zip file with a JSON header. No
pickle anywhere (arrays are read with allow_pickle=False), so a scene file cannot run code.

Format (version 1; docs/scene-format.md says the same):
- `header.json`: {"format": "ecs_engine.scene", "version": 1, "entities": N, "tables": [...]},
  each table {"components": [name, ...], "rows": n, "ids": member, "columns": [{"component":
  name, "field": name, "dtype": str, "shape": [..], "member": name}, ...]}. A component's name is
  its module and qualified class name.
- one `.npy` member per column (shape (rows, *field shape)) and per table's saved ids.

On load every table gets new ids (a world that already has entities keeps them), and every
field declared `Field(..., entity=True)` is remapped from saved ids to the new ones (an id that
named no saved entity becomes -1). Everything is checked before anything is spawned; values go
through the component's own checks (spawn_batch); if any of that fails, what was spawned is
destroyed and one SceneFileError says why: a failed load changes nothing. A save writes a
temporary file beside the target and renames it, so a failed save leaves the old file.

Not saved: resources (materials, the environment, ...) and object fields (a Python object has
no pickle-free form): saving a world with an object field is refused, naming it.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from .errors import EcsError
from .schema import Component, ObjectStore

FORMAT = "ecs_engine.scene"
VERSION = 1
HEADER_LIMIT = 16 << 20  # bytes of JSON header a scene may have


class SceneFileError(EcsError, ValueError):
    """A scene file that cannot be saved or loaded; nothing was changed."""


def component_name(ct: type[Component]) -> str:
    return f"{ct.__module__}.{ct.__qualname__}"


def _known_components() -> dict[str, type[Component]]:
    found: dict[str, type[Component]] = {}
    todo = list(Component.__subclasses__())
    while todo:
        ct = todo.pop()
        found[component_name(ct)] = ct
        todo.extend(ct.__subclasses__())
    return found


def save(world: Any, path: str | os.PathLike[str]) -> None:
    """Write the world's entities to `path` (see the module docstring)."""
    target = Path(path)
    tables, members = [], []
    for k, table in enumerate(world.tables):
        n = table.count
        if not n:
            continue
        columns = []
        for ct in sorted(table.types, key=component_name):
            if issubclass(ct, ObjectStore) or any(f.is_object for f in ct.__fields__.values()):
                raise SceneFileError(f"{ct.__name__} holds Python objects: a scene file stores only NumPy columns")
            for j, (name, f) in enumerate(ct.__fields__.items()):
                member = f"t{k}/{component_name(ct)}/{j}.npy"
                column = table.columns[(ct, name)][:n]
                columns.append(
                    {
                        "component": component_name(ct),
                        "field": name,
                        "dtype": f.dtype.str,
                        "shape": list(f.shape),
                        "member": member,
                    }
                )
                members.append((member, column))
        ids_member = f"t{k}/ids.npy"
        members.append((ids_member, table.entities[:n]))
        tables.append(
            {"components": sorted(map(component_name, table.types)), "rows": n, "ids": ids_member, "columns": columns}
        )
    header = {"format": FORMAT, "version": VERSION, "entities": sum(t["rows"] for t in tables), "tables": tables}
    temporary = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        with zipfile.ZipFile(temporary, "w", zipfile.ZIP_STORED) as archive:
            archive.writestr("header.json", json.dumps(header))
            for member, array in members:
                with archive.open(member, "w", force_zip64=True) as out:
                    np.lib.format.write_array(out, np.ascontiguousarray(array), allow_pickle=False)
        os.replace(temporary, target)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _fail(path: Path, why: str) -> SceneFileError:
    return SceneFileError(f"scene file {path}: {why}")


def _read_array(archive: zipfile.ZipFile, member: str, path: Path) -> np.ndarray:
    """A member's array, its header checked against the member's size before any allocation."""
    try:
        info = archive.getinfo(member)
    except KeyError:
        raise _fail(path, f"member {member} is missing") from None
    with archive.open(info) as data:
        try:
            version = np.lib.format.read_magic(data)
            read_header = (
                np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            )
            shape, fortran, dtype = read_header(data)
        except (ValueError, OSError, EOFError) as exc:
            raise _fail(path, f"member {member} is not a NumPy array ({exc})") from None
        if dtype.hasobject:
            raise _fail(path, f"member {member} holds Python objects")
        if int(np.prod(shape, dtype=np.int64)) * dtype.itemsize > info.file_size:
            raise _fail(path, f"member {member} claims {shape} of {dtype}, more than it holds")
        raw = data.read()
    count = int(np.prod(shape, dtype=np.int64))
    if len(raw) < count * dtype.itemsize:
        raise _fail(path, f"member {member} is truncated")
    array = np.frombuffer(raw, dtype=dtype, count=count)
    return array.reshape(shape, order="F" if fortran else "C").copy()


def _header(archive: zipfile.ZipFile, path: Path) -> dict[str, Any]:
    names = archive.namelist()
    if len(names) != len(set(names)):
        raise _fail(path, "it names a member twice")
    if any(name.startswith(("/", "\\")) or ".." in name.split("/") for name in names):
        raise _fail(path, "a member's name leaves the archive")
    try:
        info = archive.getinfo("header.json")
    except KeyError:
        raise _fail(path, "no header.json: not a scene file") from None
    if info.file_size > HEADER_LIMIT:
        raise _fail(path, f"header.json is {info.file_size} bytes, more than {HEADER_LIMIT}")
    try:
        header = json.loads(archive.read(info))
    except (ValueError, UnicodeDecodeError) as exc:
        raise _fail(path, f"header.json is not JSON ({exc})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise _fail(path, f"not a scene file (format is not {FORMAT!r})")
    version = header.get("version")
    if not isinstance(version, int) or version > VERSION or version < 1:
        raise _fail(path, f"format version {version!r}; this engine reads versions 1 to {VERSION}")
    if not isinstance(header.get("tables"), list):
        raise _fail(path, "header.json has no list of tables")
    return header


def _table(archive: zipfile.ZipFile, spec: Any, known: dict[str, type[Component]], path: Path) -> tuple:
    """One table's ids, component types and {component: {field: column}}, checked."""
    try:
        rows, names, columns, ids_member = int(spec["rows"]), list(spec["components"]), spec["columns"], spec["ids"]
    except (KeyError, TypeError, ValueError):
        raise _fail(path, "a table in header.json lacks rows, components, columns or ids") from None
    types = []
    for name in names:
        if name not in known:
            raise _fail(path, f"unknown component {name} (import the module that defines it first)")
        types.append(known[name])
    ids = _read_array(archive, str(ids_member), path)
    if ids.dtype != np.int64 or ids.shape != (rows,):
        raise _fail(path, f"table ids are {ids.dtype} {ids.shape}, expected int64 ({rows},)")
    values: dict[type[Component], dict[str, np.ndarray]] = {ct: {} for ct in types}
    for column in columns:
        ct = known.get(str(column.get("component"))) if isinstance(column, dict) else None
        if ct is None or ct not in values:
            raise _fail(path, f"a column names a component outside its table: {column!r}"[:300])
        field = ct.__fields__.get(str(column.get("field")))
        if field is None:
            raise _fail(path, f"{ct.__name__} has no field {column.get('field')!r}")
        array = _read_array(archive, str(column.get("member")), path)
        if array.dtype != field.dtype or array.shape != (rows, *field.shape):
            raise _fail(
                path, f"{field.qualname} is {array.dtype} {array.shape}, expected {field.dtype} {(rows, *field.shape)}"
            )
        values[ct][field.name] = array
    for ct, got in values.items():
        missing = set(ct.__fields__) - set(got)
        if missing:
            raise _fail(path, f"{ct.__name__} lacks its fields {sorted(missing)}")
    return ids, values


def load(path: str | os.PathLike[str], world: Any) -> tuple[Any, dict[int, int]]:
    """Load the scene at `path` into `world` (World.load makes a new one). Returns the world and
    the map from saved ids to new ids. Raises SceneFileError (and changes nothing) on a bad file."""
    file = Path(path)
    if world.deferring:
        raise SceneFileError("a scene cannot be loaded from inside a system or a query loop")
    try:
        with zipfile.ZipFile(file) as archive:
            header = _header(archive, file)
            known = _known_components()
            tables = [_table(archive, spec, known, file) for spec in header["tables"]]
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError) as exc:
        raise _fail(file, f"unreadable ({exc})") from None
    spawned: list[np.ndarray] = []
    mapping: dict[int, int] = {}
    try:
        for ids, values in tables:
            bundle = []
            for ct, fields in values.items():
                safe = {n: (np.full_like(v, -1) if ct.__fields__[n].entity else v) for n, v in fields.items()}
                bundle.append(ct(**safe))
            new = world.spawn_batch(len(ids), *bundle)
            spawned.append(new)
            mapping.update(zip(ids.tolist(), new.tolist()))
        old_ids = np.fromiter(mapping.keys(), np.int64, len(mapping))
        new_ids = np.fromiter(mapping.values(), np.int64, len(mapping))
        order = np.argsort(old_ids)
        old_sorted, new_sorted = old_ids[order], new_ids[order]
        for (_, values), new in zip(tables, spawned):
            for ct, fields in values.items():
                remapped = {}
                for name, column in fields.items():
                    if ct.__fields__[name].entity:
                        at = np.minimum(np.searchsorted(old_sorted, column), max(len(old_sorted) - 1, 0))
                        hit = (len(old_sorted) > 0) & (old_sorted[at] == column)
                        remapped[name] = np.where(hit, new_sorted[at], -1)
                if remapped and len(new):
                    world.set(new, ct, **remapped)
    except (EcsError, ValueError, TypeError) as exc:
        for ids in spawned:
            world.destroy(ids)
        raise _fail(file, str(exc)) from None
    return world, mapping
