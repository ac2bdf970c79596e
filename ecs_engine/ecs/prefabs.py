"""Prefabs: a saved scene file used as a template, read once and spawned many times in bulk.

    enemy = Prefab.load("enemy.scene", world)        # checked as World.load checks a scene
    ids = enemy.spawn(world, 1000, overrides={Transform: {"position": positions}})  # (1000, len(enemy))

- Each copy gets new entities; entity fields (`Field(..., entity=True)`, e.g. Parent) that name
  an entity of the prefab name that entity's copy, and any other id becomes -1 (as a load).
- `overrides` go to the prefab's roots: its entities whose entity fields name none of its other
  entities (with Parent, the top of each tree). Per field a value for every copy, or an array of
  one row per copy (`(count, *field shape)`); checked as a spawn checks values.
- Spawning is one `spawn_batch` per table of the file whatever the count; inside a system it is
  deferred like any spawn, and the returned ids are valid from the sync point on. Observers see
  the copies once, with their entity fields already pointing at the copies.
- The file's resources (materials, meshes) go into the world once, when it is loaded, as
  World.load puts them; its handle columns are remapped then.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from contextlib import nullcontext
from typing import Any

import numpy as np

from .commands import Set
from .scene_file import ReadScene, ResourceCodec, SceneFileError, fail, read_scene
from .schema import Component

Overrides = Mapping[type[Component], Mapping[str, Any]]


class Prefab:
    """A scene file read once (`Prefab.load`), to spawn as many copies as asked."""

    def __init__(self, scene: ReadScene) -> None:
        self.file = scene.file
        self.tables = scene.tables
        self.entities = scene.saved_ids[scene.order]  # saved ids, sorted: the columns `spawn` returns
        self._rows = [np.searchsorted(self.entities, t.ids) for t in self.tables]  # each row's column
        self._links: list[dict[tuple[type[Component], str], np.ndarray]] = []  # entity field -> column, -1: none
        self._roots: list[np.ndarray] = []
        for t, rows in zip(self.tables, self._rows):
            links, root = {}, np.ones(len(t.ids), bool)
            for ct, fields in t.values.items():
                for name, saved in fields.items():
                    if ct.__fields__[name].entity:
                        at = np.minimum(np.searchsorted(self.entities, saved), len(self.entities) - 1)
                        column = np.where(self.entities[at] == saved, at, -1)
                        links[(ct, name)] = column
                        root &= (column < 0) | (column == rows)  # naming another of its entities: not a root
            self._links.append(links)
            self._roots.append(root)
        self.roots = np.zeros(len(self.entities), bool)
        for rows, root in zip(self._rows, self._roots):
            self.roots[rows[root]] = True

    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str],
        world: Any,
        *,
        resources: Iterable[ResourceCodec] | None = None,
        components: Any = None,
    ) -> Prefab:
        """Read and check the scene file at `path` (SceneFileError if it cannot be loaded, or holds
        no entity); its resources go into `world` now (see the module)."""
        scene = read_scene(path, world, resources=resources, components=components)
        if not len(scene.saved_ids):
            raise fail(scene.file, "it holds no entities: nothing to spawn as a prefab")
        for k, t in enumerate(scene.tables):  # its values checked now, not at the first spawn
            for ct, fields in t.values.items():
                who = lambda row, k=k: f"table {k}, row {row}"
                try:
                    fields.update({name: ct.__fields__[name].coerce(v, len(t.ids), who) for name, v in fields.items()})
                    ct.check(fields, who)
                except ValueError as exc:
                    raise fail(scene.file, str(exc)) from None
        for ready in scene.prepared:
            ready.commit(world)
        return cls(scene)

    def __len__(self) -> int:
        """Entities in one copy."""
        return len(self.entities)

    def __repr__(self) -> str:
        return f"<prefab {self.file.name}: {len(self)} entities, {int(self.roots.sum())} roots>"

    def spawn(self, world: Any, count: int = 1, overrides: Overrides | None = None) -> np.ndarray:
        """Spawn `count` copies; their ids, shape (count, len(self)), columns in `self.entities`' order."""
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
            raise ValueError(f"prefab {self.file.name}: count is a whole number >= 0, got {count!r}")
        count = int(count)
        chosen = self._overrides(overrides or {}, count)
        new = np.empty((count, len(self)), np.int64)
        if not count:
            return new
        columns = [self._columns(k, count, chosen) for k in range(len(self.tables))]
        spawned: list[np.ndarray] = []
        deferring = world.deferring
        with nullcontext() if deferring else world.observers_held():
            try:
                for k, t in enumerate(self.tables):  # entity fields -1 until every copy has its ids
                    links = self._links[k]
                    bundle = [
                        ct(**{n: np.full(len(v), -1, np.int64) if (ct, n) in links else v for n, v in c.items()})
                        for ct, c in columns[k].items()
                    ]
                    spawned.append(world.spawn_batch(count * len(t.ids), *bundle))
                    new[:, self._rows[k]] = spawned[-1].reshape(count, len(t.ids))
                for k in range(len(self.tables)):
                    self._link(world, k, new, spawned[k], columns[k], chosen, deferring)
            except BaseException:
                for ids in spawned:  # observers held: they hear of neither the copies nor this
                    world.destroy(ids)
                raise
        return new

    def _overrides(self, overrides: Overrides, count: int) -> dict[type[Component], dict[str, np.ndarray]]:
        """The override values, checked, each (1 or count, *field shape)."""
        if not isinstance(overrides, Mapping):
            raise TypeError(f"prefab overrides are {{Component: {{field: value}}}}, got {type(overrides).__name__}")
        root_types = {ct for t, root in zip(self.tables, self._roots) if root.any() for ct in t.types}
        chosen = {}
        for ct, fields in overrides.items():
            if not (isinstance(ct, type) and issubclass(ct, Component)):
                raise TypeError(f"prefab overrides are keyed by component types, got {ct!r}")
            if ct not in root_types:
                raise ValueError(f"prefab {self.file.name}: no root entity has {ct.__name__} to override")
            if not isinstance(fields, Mapping):
                raise TypeError(f"overrides[{ct.__name__}] is {{field: value}}, got {type(fields).__name__}")
            unknown = sorted(set(fields) - set(ct.__fields__))
            if unknown:
                raise TypeError(f"{ct.__name__} has no field(s) {unknown}")
            who = lambda row: f"copy {row} of prefab {self.file.name}"
            chosen[ct] = {name: ct.__fields__[name].coerce(v, count, who) for name, v in fields.items()}
        return chosen

    def _columns(self, k: int, count: int, chosen: dict[type[Component], dict[str, np.ndarray]]) -> dict[Any, Any]:
        """Table k's values for `count` copies (copy by copy), the roots' overridden."""
        t, root, rows = self.tables[k], self._roots[k], len(self.tables[k].ids)
        out: dict[type[Component], dict[str, np.ndarray]] = {}
        for ct in t.types:
            saved = t.values[ct]
            values = {name: np.tile(v, (count,) + (1,) * (v.ndim - 1)) for name, v in saved.items()}
            for name, value in chosen.get(ct, {}).items() if root.any() else ():
                f = ct.__fields__[name]
                if name not in values:  # a field the file does not have: its default
                    values[name] = np.broadcast_to(f.default, (count * rows, *f.shape)).copy()
                values[name].reshape(count, rows, *f.shape)[:, root] = value[:, None]
            if ct in chosen:
                ct.check(values, lambda row: f"copy {row // max(rows, 1)} of prefab {self.file.name}")
            out[ct] = values
        return out

    def _link(
        self,
        world: Any,
        k: int,
        new: np.ndarray,
        ids: np.ndarray,
        columns: dict[Any, Any],
        chosen: dict[type[Component], dict[str, np.ndarray]],
        deferring: bool,
    ) -> None:
        """Point table k's entity fields at the copies (an override of a root's wins)."""
        links = self._links[k]
        for ct in {ct for ct, _ in links}:
            values = dict(columns[ct])
            for (c, name), column in links.items():
                if c is ct:
                    linked = np.where(column >= 0, new[:, np.maximum(column, 0)], -1)
                    if name in chosen.get(ct, {}):
                        linked[:, self._roots[k]] = chosen[ct][name][:, None]
                    values[name] = linked.reshape(-1)
            if deferring:  # inside a system: queued behind the spawn (a set there would need Parent in writes)
                world._commands.push(Set(ids, ct, values, lambda row: f"a copy of prefab {self.file.name}"))
            else:
                world.set(ids, ct, **values)


def spawn_prefab(
    world: Any, path: str | os.PathLike[str], count: int = 1, overrides: Overrides | None = None, **load: Any
) -> np.ndarray:
    """Load the prefab at `path` and spawn `count` copies (`Prefab.load` once to spawn it often)."""
    return Prefab.load(path, world, **load).spawn(world, count, overrides)


__all__ = ["Prefab", "SceneFileError", "spawn_prefab"]
