"""Queries: the tables holding a set of component types, handed out as per-table column views."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from typing import Any, Protocol

import numpy as np

from .errors import AccessError
from .schema import Component, Field, ObjectStore, schema_of
from .table import ArchetypeTable, ColumnKey

_SCAN_LOCK = threading.Lock()


class QueryHost(Protocol):
    """What a query needs of its world: change ticks and the deferral of structural changes
    while its loop runs (World provides them)."""

    def write_tick(self) -> int: ...

    def system_last_run_tick(self) -> int: ...

    def begin_iteration(self) -> None: ...

    def end_iteration(self) -> None: ...


class ComponentView:
    """The columns of one component in one table; `view.position` is an (n, 3) array view.

    Fields are plain instance attributes (fast to read). Assigning one writes into the column
    (`view.position = p` copies p in) instead of rebinding, so no update is silently lost."""

    _component: type[Component]

    def __init__(self, component: type[Component], arrays: dict[str, np.ndarray]) -> None:
        self.__dict__.update(arrays)
        object.__setattr__(self, "_component", component)

    def __getattr__(self, name: str) -> np.ndarray:
        raise AttributeError(f"{self._component.__name__} has no field {name!r}")

    def __setattr__(self, name: str, value: Any) -> None:
        if name not in self._component.__fields__:
            raise AttributeError(f"{self._component.__name__} has no field {name!r}")
        self.__dict__[name][...] = value

    def __repr__(self) -> str:
        return f"<{self._component.__name__} columns: {', '.join(self._component.__fields__)}>"


class Batch:
    """One matched table: `entities` (ids) and column views, read-only where not written.

    A query keeps its batches while their table's layout is unchanged (same rows, same
    arrays), so iterating an unchanged world costs little more than a loop over tables."""

    __slots__ = ("_query", "_views", "entities", "table")

    def __init__(self, table: ArchetypeTable, query: Query) -> None:
        self.table = table
        self._query = query
        self._views: dict[Any, ComponentView] = {}
        ids = table.entities[: table.count]
        ids.flags.writeable = False
        self.entities = ids

    def __len__(self) -> int:
        return self.table.count

    def __getitem__(self, key: type | Field) -> Any:
        if isinstance(key, Field):
            return self.view(key.component).__dict__[key.name]  # type: ignore[arg-type]
        view = self.view(key)
        if issubclass(view._component, ObjectStore):
            return view.value  # a plain Python class stored as objects: hand out the object column
        return view

    def view(self, component: type) -> ComponentView:
        view = self._views.get(component)
        if view is not None:
            return view
        ct = schema_of(component)
        if ct not in self._query.access:
            raise AccessError(f"query over {self._query.describe()} does not include {ct.__name__}")
        writable = ct in self._query.write
        arrays = {}
        n = self.table.count
        for name in ct.__fields__:
            arr = self.table.columns[(ct, name)][:n]
            if not writable:
                arr.flags.writeable = False
            arrays[name] = arr
        view = self._views[component] = ComponentView(ct, arrays)
        return view


class Query:
    """Matches tables holding all `required` and `with_` types and none of `without`.

    The matched table list is cached and extended as new tables appear. Iterating yields one
    `Batch` per non-empty table; structural changes made meanwhile are deferred to the next
    sync point, so the views stay valid for the whole loop.
    """

    def __init__(
        self,
        world: QueryHost,
        tables: list[ArchetypeTable],
        required: tuple[type[Component], ...],
        with_: frozenset[type[Component]],
        without: frozenset[type[Component]],
        write: frozenset[type[Component]],
    ) -> None:
        self._world = world
        self._all_tables = tables  # the storage's list, appended to as tables appear
        self.required = required
        self.with_ = with_
        self.without = without
        self.write = write
        self.access = frozenset(required)
        self._all = frozenset(required) | with_
        self._write_keys: list[ColumnKey] = [(ct, name) for ct in write for name in ct.__fields__]
        self._tables: list[ArchetypeTable] = []
        self._scanned = 0
        self._batches: dict[int, tuple[int, Batch]] = {}  # table id -> (table version, batch)
        self._changed_keys: dict[tuple[type, ...], list[ColumnKey]] = {}  # iter(changed=...)'s columns

    def describe(self) -> str:
        parts = [", ".join(t.__name__ for t in self.required)]
        if self.with_:
            parts.append("with " + ", ".join(sorted(t.__name__ for t in self.with_)))
        if self.without:
            parts.append("without " + ", ".join(sorted(t.__name__ for t in self.without)))
        return "(" + "; ".join(parts) + ")"

    def _refresh(self) -> list[ArchetypeTable]:
        tables = self._all_tables
        if self._scanned < len(tables):
            with _SCAN_LOCK:  # systems of a parallel stage may share this query
                n = len(tables)
                fresh = tables[self._scanned : n]
                found = [t for t in fresh if self._all <= t.type_set and not (self.without & t.type_set)]
                self._tables = self._tables + found  # a new list: a loop over the old one goes on undisturbed
                self._scanned = n
        return self._tables

    @property
    def tables(self) -> list[ArchetypeTable]:
        return list(self._refresh())

    def __iter__(self) -> Iterator[Batch]:
        return self.iter()

    def iter(self, changed: tuple[type, ...] = (), since: int | None = None) -> Iterator[Batch]:
        """Yield batches; with `changed`, only tables where one of those columns was written
        after tick `since` (inside a system, `since` defaults to its last run)."""
        world = self._world
        tables = self._tables if self._scanned == len(self._all_tables) else self._refresh()
        if not tables:
            return  # no table matches: nothing to yield, no iteration to open (a per-frame saving)
        changed_keys: list[ColumnKey] = []
        if changed:
            if since is None:
                since = world.system_last_run_tick()
            kept = self._changed_keys.get(changed) if type(changed) is tuple else None
            if kept is None:
                for t in changed:
                    ct = schema_of(t)
                    changed_keys.extend((ct, name) for name in ct.__fields__)
                if type(changed) is tuple:  # the same filter every frame: its columns found once
                    self._changed_keys[changed] = changed_keys
            else:
                changed_keys = kept
        tick = world.write_tick() if self._write_keys else 0
        world.begin_iteration()
        try:
            for table in tables:
                if table.count == 0:
                    continue
                if changed_keys and not _changed(table, changed_keys, since):  # type: ignore[arg-type]
                    continue
                for key in self._write_keys:
                    table.column_ticks[key] = tick
                cached = self._batches.get(table.id)
                if cached is None or cached[0] != table.version:
                    cached = self._batches[table.id] = (table.version, Batch(table, self))
                yield cached[1]
        finally:
            world.end_iteration()

    def count(self) -> int:
        return sum(t.count for t in self._refresh())

    def entities(self) -> np.ndarray:
        tables = self._refresh()
        parts = [t.entities[: t.count] for t in tables if t.count]
        return np.concatenate(parts) if parts else np.empty(0, dtype=np.int64)

    def column(self, field: Field) -> np.ndarray:
        """All rows of one field, concatenated across tables (a copy)."""
        ct = field.component
        assert ct is not None
        tables = self._refresh()
        parts = [t.columns[(ct, field.name)][: t.count] for t in tables if t.count]
        if not parts:
            return np.empty((0, *field.shape), dtype=field.dtype)
        return np.concatenate(parts)


def _changed(table: ArchetypeTable, keys: list[ColumnKey], since: int) -> bool:
    ticks = table.column_ticks
    for k in keys:  # a loop, not any() over a generator: asked per table per frame
        tick = ticks.get(k)
        if tick is not None and tick > since:
            return True
    return False


def check_access(
    system_name: str,
    reads: frozenset[type],
    writes: frozenset[type],
    required: tuple[type[Component], ...],
    write: frozenset[type[Component]],
) -> None:
    undeclared = [t.__name__ for t in required if t not in reads and t not in writes]
    if undeclared:
        raise AccessError(f"system {system_name} queries {undeclared} but does not declare them")
    not_writable = [t.__name__ for t in write if t not in writes]
    if not_writable:
        raise AccessError(f"system {system_name} asks to write {not_writable} but declares them read-only")
