"""Saved scenes: a world's entities as NumPy columns in one zip file with a JSON header. No pickle
anywhere (arrays are read with allow_pickle=False, object dtypes are refused both ways), so
opening a scene file cannot run code. docs/scene-format.md is the full specification.

Format version 2 (version 1 files, without resources, load too): a zip archive, its members
stored (floats barely compress; stored members go at disk speed; deflated ones are read too):
- `header.json`: {"format": "ecs_engine.scene", "version": 2, "engine": "0.1.0", "entities": N,
  "tables": [...], "resources": [...], "not_saved": [...]}. Per archetype table: "components"
  (stable names, below), "rows", "ids" (member of its saved entity ids), "columns": per field
  {"component", "field", "dtype" (numpy's dtype.str), "shape" (per entity), "member"}. Per
  resource: {"name", "module", "doc" (JSON), "arrays": {key: {"member", "dtype", "shape"}}}.
  "not_saved": the world's resources that no codec saved (JobPool, input state...).
- one `.npy` member per column, shape (rows, *field shape), and per table's ids (int64).

A component's stable name (scene_names.py) is its class's own `scene_name` attribute if any,
else module and qualified name: the loader finds it among the Component subclasses imported (or
`components=`; of two with one name, as after a game module is imported again, the one its
module binds now). A class of `__main__` is named for the module its script is when imported
(`python catch.py` saves `catch.Star`, which `ecs-engine play catch.py` loads); one typed in the
REPL is refused at save time.

Loading gives every entity a new id (a world's own entities stay: nothing collides) and returns
an IdMap, saved id -> new id; `Field(..., entity=True)` fields are rewritten to the new ids (-1
for an id that named no saved entity). The whole file is checked before anything spawns; values
then pass the components' own checks (spawn_batch). On any failure what was spawned is destroyed
and one SceneFileError says why.

Resources (materials, environment) and session assets (meshes) are saved by codecs plugged in
here (ResourceCodec; render/assets/scene_assets.py has the stock ones), so the core needs no renderer:
a codec saves JSON plus arrays and, on load, may rewrite handle columns through lookup tables.
Only a regular file is opened (ecs_engine/user_files.py); scene_archive.py reads and checks its
members, each resource array's size shown to its codec (`check_array`) before it is read.
"""

from __future__ import annotations

import json
import os
import secrets
import zipfile
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ..user_files import SCENE, UserFileError, open_user_file
from .errors import EcsError
from .scene_archive import (
    ARRAY_KEY,
    FORMAT,
    READS,
    SavedResource,
    SavedTable,
    SceneArchive,
    SceneFileError,
    check,
    fail,
)
from .scene_names import check_saveable, component_name, known_components, main_module_name
from .schema import Component

__all__ = ["FORMAT", "READS", "VERSION", "IdMap", "ResourceCodec", "SavedResource", "SceneFileError"]
__all__ += ["component_name", "known_components", "load", "load_world", "register_codec", "save", "save_world"]
__all__ += ["main_module_name"]  # scene_names.py's, imported from here by app.py

VERSION = 2

Remaps = dict[tuple[type[Component], str], np.ndarray]
try:
    _ENGINE = metadata.version("ecs_engine")
except metadata.PackageNotFoundError:  # run from a checkout that is not installed
    _ENGINE = "unknown"


class PreparedResource(Protocol):
    """A resource read and checked, not yet in the world."""

    def remaps(self) -> Remaps: ...  # per (component, field): saved value -> target's (-1: none)

    def commit(self, world: Any) -> None: ...  # into the world once every entity is placed; never fails


class ResourceCodec(Protocol):
    """How one resource (or session asset table) goes into a scene file and comes back."""

    name: str  # its key in the header
    resource_types: tuple[Any, ...]  # the world.resources keys it saves (for "not_saved")

    def save(self, world: Any) -> SavedResource | None: ...  # None: nothing to save

    # check `saved` and plan it against `world`, changing nothing there; ValueError if bad
    def read(self, saved: SavedResource, world: Any) -> PreparedResource: ...


_codecs: dict[str, ResourceCodec] = {}


def register_codec(codec: ResourceCodec) -> None:
    """Make `codec` one of the defaults of save_world and load_world (a later one of the same name
    replaces it). render/assets/scene_assets.py registers the materials and environment codecs."""
    if not ARRAY_KEY.match(codec.name):
        raise ValueError(f"a codec's name is 1-64 of [A-Za-z0-9_], got {codec.name!r}")
    _codecs[codec.name] = codec


def registered_codecs() -> list[ResourceCodec]:
    return list(_codecs.values())


class IdMap(Mapping[int, int]):
    """Saved entity id -> new id, kept as sorted arrays (a dict of a million ints costs a second)."""

    def __init__(self, saved: np.ndarray, new: np.ndarray, order: np.ndarray | None = None) -> None:
        order = np.argsort(saved) if order is None else order
        self.saved, self.new = saved[order], new[order]

    def remap(self, ids: np.ndarray) -> np.ndarray:
        """New ids for saved ones, vectorised; -1 where an id named no saved entity."""
        ids = np.asarray(ids, np.int64)
        if not len(self.saved):
            return np.full(ids.shape, -1, np.int64)
        at = np.minimum(np.searchsorted(self.saved, ids), len(self.saved) - 1)
        return np.where(self.saved[at] == ids, self.new[at], -1)

    def __getitem__(self, eid: int) -> int:
        if (found := int(self.remap(np.array([eid], np.int64))[0])) < 0:
            raise KeyError(eid)
        return found

    def __iter__(self) -> Iterator[int]:
        return iter(self.saved.tolist())

    def __len__(self) -> int:
        return len(self.saved)


# ------------------------------------------------------------------------------------- saving
def save_world(world: Any, path: str | os.PathLike[str], *, resources: Iterable[ResourceCodec] | None = None) -> None:
    """Write the world's entities, and what `resources` (default: the registered codecs) save, to
    `path`. Written to a temporary file beside it and renamed, so a failed save keeps the old file."""
    target = Path(path)
    if world.deferring:
        raise SceneFileError("a scene cannot be saved from inside a system or a query loop")
    members: list[tuple[str, np.ndarray]] = []
    tables = []
    for k, table in enumerate(t for t in world.tables if t.count):
        n, columns = table.count, list[dict[str, Any]]()
        for ct in sorted(table.types, key=component_name):
            check_saveable(ct, target)
            for name, f in ct.__fields__.items():
                why = "it holds Python objects, which only pickle could store (a scene file holds NumPy columns)"
                check(not f.is_object, target, f"cannot save {ct.__name__}.{name}: {why}")
                member = f"tables/{k}/{len(columns)}.npy"
                columns.append({"component": component_name(ct), "field": name} | _described(member, f.dtype, f.shape))
                members.append((member, table.columns[(ct, name)][:n]))
        members.append((f"tables/{k}/ids.npy", table.entities[:n]))
        names = sorted(map(component_name, table.types))
        tables.append({"components": names, "rows": n, "ids": f"tables/{k}/ids.npy", "columns": columns})
    saved_resources, covered = [], set[Any]()
    for codec in _chosen(resources):
        covered.update(codec.resource_types)
        try:
            saved = codec.save(world)
        except (ValueError, TypeError, KeyError) as exc:
            raise SceneFileError(f"cannot save resource {codec.name!r}: {exc}") from None
        if saved is None:
            continue
        arrays = {}
        for key, array in saved.arrays.items():
            array = np.asarray(array)
            check(bool(ARRAY_KEY.match(key)) and not array.dtype.hasobject, target, f"{codec.name}: array {key!r}")
            arrays[key] = _described(f"resources/{codec.name}/{key}.npy", array.dtype, array.shape)
            members.append((arrays[key]["member"], array))
        module = type(codec).__module__
        saved_resources.append({"name": codec.name, "module": module, "doc": saved.doc, "arrays": arrays})
    not_saved = sorted(_resource_name(key) for key in world.resources if key not in covered)
    header = {"format": FORMAT, "version": VERSION, "engine": _ENGINE, "entities": sum(t["rows"] for t in tables)}
    header |= {"tables": tables, "resources": saved_resources, "not_saved": not_saved}
    try:
        text = json.dumps(header, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise SceneFileError(f"a resource's document is not plain JSON: {exc}") from None
    _write(target, text, members)


def _described(member: str, dtype: np.dtype, shape: tuple[int, ...]) -> dict[str, Any]:
    return {"dtype": dtype.str, "shape": list(shape), "member": member}


def _resource_name(key: Any) -> str:
    return f"{key.__module__}.{key.__qualname__}" if isinstance(key, type) else repr(key)[:100]


def _write(target: Path, header: str, members: list[tuple[str, np.ndarray]]) -> None:
    temporary = target.with_name(f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    try:
        with open(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), "wb") as raw:
            with zipfile.ZipFile(raw, "w", zipfile.ZIP_STORED) as archive:
                archive.writestr("header.json", header)
                for member, array in members:
                    with archive.open(member, "w", force_zip64=True) as out:
                        np.lib.format.write_array(out, np.ascontiguousarray(array), allow_pickle=False)
        os.replace(temporary, target)
    except BaseException as exc:
        temporary.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise SceneFileError(f"cannot write scene file {target}: {exc.strerror or exc}") from None
        raise


def _chosen(resources: Iterable[ResourceCodec] | None) -> list[ResourceCodec]:
    codecs = registered_codecs() if resources is None else list(resources)
    names = [c.name for c in codecs]
    if len(set(names)) != len(names):
        raise SceneFileError(f"two resource codecs share a name: {sorted(names)}")
    return codecs


# ------------------------------------------------------------------------------------ loading
def load_world(
    path: str | os.PathLike[str],
    world: Any,
    *,
    resources: Iterable[ResourceCodec] | None = None,
    components: Mapping[str, type[Component]] | Iterable[type[Component]] | None = None,
) -> tuple[Any, IdMap]:
    """Add the scene at `path` to `world` (World.load passes a new one). `resources`: the codecs
    (default: the registered ones); `components`: name -> class, or classes (default: every
    Component subclass imported). Returns the world and the IdMap. Raises SceneFileError and
    changes nothing on a bad file. Observers see the loaded entities at once, remapped."""
    scene = read_scene(path, world, resources=resources, components=components)
    with world.observers_held():
        return world, _spawn(scene.file, world, scene.tables, (scene.saved_ids, scene.order), scene.prepared)


@dataclass
class ReadScene:
    """A scene file read and checked, its handle columns remapped, nothing spawned yet."""

    file: Path
    tables: list[SavedTable]
    saved_ids: np.ndarray  # every table's ids, in table order
    order: np.ndarray  # argsort of saved_ids
    prepared: list[Any]  # its resources, planned against the world, not committed


def read_scene(
    path: str | os.PathLike[str],
    world: Any,
    *,
    resources: Iterable[ResourceCodec] | None = None,
    components: Mapping[str, type[Component]] | Iterable[type[Component]] | None = None,
) -> ReadScene:
    """The first half of load_world (prefabs.py spawns what it reads many times)."""
    file = Path(path)
    if world.deferring:
        raise SceneFileError("a scene cannot be loaded from inside a system or a query loop")
    known: Any = known_components() if components is None else components
    if not isinstance(known, Mapping):
        known = {component_name(ct): ct for ct in known}
    codecs = {c.name: c for c in _chosen(resources)}
    try:
        with open_user_file(file, SCENE) as raw, zipfile.ZipFile(raw) as archive:
            reader = SceneArchive(archive, file, os.fstat(raw.fileno()).st_size)
            header = reader.header()
            tables = [reader.table(k, spec, known) for k, spec in enumerate(header["tables"])]
            saved = [reader.resource(spec, codecs) for spec in header["resources"]]
            reader.all_used()
    except SceneFileError:
        raise
    except UserFileError as exc:  # a FIFO, a device, a directory
        raise fail(file, exc.why) from None
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError, RuntimeError, NotImplementedError) as exc:
        raise fail(file, f"unreadable ({exc})") from None
    except (ValueError, TypeError, KeyError) as exc:  # a value in the file that no check above caught
        raise fail(file, f"malformed ({exc})") from None
    if header["entities"] != sum(len(t.ids) for t in tables):
        raise fail(file, f"the header counts {header['entities']} entities, its tables hold another number")
    saved_ids = np.concatenate([t.ids for t in tables]) if tables else np.empty(0, np.int64)
    order = np.argsort(saved_ids)
    ordered = saved_ids[order]
    if len(ordered) and (ordered[0] <= 0 or (ordered[1:] == ordered[:-1]).any()):
        raise fail(file, "its saved entity ids are not unique positive ids")
    prepared = [_prepare(file, codecs, spec, world) for spec in saved]
    remaps: Remaps = {}
    for ready in prepared:
        for key, table in ready.remaps().items():
            if key in remaps:
                raise fail(file, f"two resources remap {key[0].__name__}.{key[1]}")
            remaps[key] = np.asarray(table, np.int64)
    for k, t in enumerate(tables):
        _apply(file, k, t, remaps)
    return ReadScene(file, tables, saved_ids, order, prepared)


def _prepare(file: Path, codecs: dict[str, ResourceCodec], spec: tuple[str, str, SavedResource], world: Any) -> Any:
    name, module, saved = spec
    codec = codecs.get(name)
    if codec is None:
        why = f"no codec was given for its resource {name!r} (import {module[:100]} or pass resources=)"
        raise fail(file, why)
    try:
        return codec.read(saved, world)
    except (ValueError, TypeError, KeyError, LookupError) as exc:
        raise fail(file, f"resource {name!r}: {exc}") from None


def _apply(file: Path, k: int, table: SavedTable, remaps: Remaps) -> None:
    """Rewrite handle columns through the codecs' lookup tables (saved value -> target's)."""
    for (ct, name), lookup in remaps.items():
        column = table.values.get(ct, {}).get(name)
        if column is None or not len(column):
            continue
        ok = (column >= 0) & (column < len(lookup))
        new = lookup[np.where(ok, column, 0)] if len(lookup) else np.full(len(column), -1, np.int64)
        bad = ~ok | (new < 0)
        if bad.any():
            value = column[np.argmax(bad)]
            raise fail(file, f"table {k}: {ct.__name__}.{name} {value} names nothing the scene saved")
        table.values[ct][name] = new.astype(column.dtype)


def _spawn(
    file: Path, world: Any, tables: list[SavedTable], saved: tuple[np.ndarray, ...], prepared: list[Any]
) -> IdMap:
    """Spawn every table (entity fields as -1 first), then point the entity fields at the new
    ids and commit the resources; on any failure destroy what was spawned."""
    spawned: list[np.ndarray] = []
    try:
        for k, t in enumerate(tables):
            bundle = []
            for ct, fields in t.values.items():
                safe = {n: (np.full(len(v), -1, np.int64) if ct.__fields__[n].entity else v) for n, v in fields.items()}
                bundle.append(ct(**safe))
            try:
                spawned.append(world.spawn_batch(len(t.ids), *bundle))
            except (EcsError, ValueError, TypeError) as exc:  # a value the component's checks refuse
                names = ", ".join(ct.__name__ for ct in t.types) or "no components"
                raise fail(file, f"table {k} ({names}): {exc}") from None
            _exact_units(world, t, spawned[-1])
        ids = IdMap(saved[0], np.concatenate(spawned) if spawned else np.empty(0, np.int64), saved[1])
        for t, new in zip(tables, spawned):
            for ct, fields in t.values.items():
                if any(ct.__fields__[n].entity for n in fields):
                    full = {n: ids.remap(v) if ct.__fields__[n].entity else v for n, v in fields.items()}
                    world.set(new, ct, **full)  # every field given: no per-entity partial check
        for ready in prepared:
            ready.commit(world)
    except BaseException as exc:
        for new in spawned:
            world.destroy(new)
        if isinstance(exc, (EcsError, ValueError, TypeError)) and not isinstance(exc, SceneFileError):
            raise fail(file, str(exc)) from exc
        raise
    return ids


def _exact_units(world: Any, t: SavedTable, new: np.ndarray) -> None:
    """Spawning normalised the unit fields (quaternions), which can move a row that was unit
    already by an ulp: put back the saved rows that were unit to rounding, so a round trip is exact."""
    table, row = world.locate(int(new[0])) if len(new) else (None, 0)
    rows = slice(row, row + len(new))
    if table is None or not np.array_equal(table.entities[rows], new):
        return  # not placed as one run of rows: keep the normalised values
    for ct, fields in t.values.items():
        for name, saved in fields.items():
            if ct.__fields__[name].unit:  # |q|^2 - 1 is about 2 (|q| - 1): within a few ulps of unit
                unit = np.abs(np.einsum("...i,...i->...", saved, saved) - 1) <= 16 * np.finfo(saved.dtype).eps
                np.copyto(table.columns[(ct, name)][rows], saved, where=unit[..., None])


# the names World.save and World.load call
save = save_world
load = load_world
