"""The world: entities in archetype tables, structural changes, queries and change ticks."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

import numpy as np

from .entities import INDEX_MASK, RESERVED, EntityIndex
from .errors import (
    AccessError,
    DeadEntityError,
    EcsError,
    MissingComponentError,
    describe_entity,
)
from .query import Query, check_access
from .schema import Component, ObjectStore, closure, object_component
from .table import ArchetypeTable

if TYPE_CHECKING:
    from .schedule import System

Checked = dict[type[Component], dict[str, np.ndarray]]


def _new_entity(row: int) -> str:
    return "new entity" if row == 0 else f"new entity (row {row} of the batch)"


def schema_of(t: Any) -> type[Component]:
    """The storage schema for a component type; plain Python classes map to an object column."""
    if isinstance(t, type):
        return t if issubclass(t, Component) else object_component(t)
    raise TypeError(f"expected a component type (a class), got {t!r}")


class World:
    """Holds every entity and component. See the package docstring for the rules of use."""

    def __init__(self) -> None:
        self._index = EntityIndex()
        self._tables: list[ArchetypeTable] = []
        self._table_ids: dict[frozenset[type[Component]], int] = {}
        self._queries: dict[tuple[Any, ...], Query] = {}
        self._queries_by_call: dict[tuple[Any, ...], Query] = {}  # as called (see query)
        self._stamp_keys: dict[tuple[type, ...], list[tuple[Any, str]]] = {}  # see change_stamp
        self._closures: dict[frozenset[type[Component]], frozenset[type[Component]]] = {}
        self.tick = 0
        # Bumped by every spawn, destroy, add and remove that is applied (not when queued).
        self.structure_version = 0
        self._commands: list[tuple[Any, ...]] = []
        self._pending_destroy: set[int] = set()
        self._iter_depth = 0
        self._defer_depth = 0
        self._system: System | None = None
        self._system_tick = 0
        # Singletons shared by systems (render origin, input state, ...), keyed by type.
        self.resources: dict[Any, Any] = {}
        self._table_for(frozenset())

    schema_of = staticmethod(schema_of)

    # ------------------------------------------------------------------ state
    def __len__(self) -> int:
        """Entities placed in tables (spawns still deferred are not counted)."""
        return sum(t.count for t in self._tables)

    @property
    def tables(self) -> tuple[ArchetypeTable, ...]:
        return tuple(self._tables)

    @property
    def deferring(self) -> bool:
        return self._iter_depth > 0 or self._defer_depth > 0 or self._system is not None

    def entities(self) -> np.ndarray:
        parts = [t.entities[: t.count] for t in self._tables if t.count]
        return np.concatenate(parts) if parts else np.empty(0, dtype=np.int64)

    def memory_bytes(self) -> int:
        """Bytes held by columns, id columns and the entity index."""
        return self._index.nbytes() + sum(t.nbytes() for t in self._tables)

    def shrink_to_fit(self) -> None:
        """Release the spare capacity that growth by doubling leaves behind."""
        for t in self._tables:
            t.shrink_to_fit()
        self._index.shrink_to_fit()

    def is_alive(self, eid: int) -> bool:
        return self._index.valid_one(int(eid)) and int(self._index.table[int(eid) & INDEX_MASK]) >= 0

    def has(self, eid: int, component_type: type) -> bool:
        table, _ = self._locate(int(eid))
        return table.has(schema_of(component_type))

    def components(self, eid: int) -> tuple[type[Component], ...]:
        table, _ = self._locate(int(eid))
        return table.types

    def change_stamp(self, eid: int, *component_types: type) -> tuple[int, ...]:
        """A value that stays equal while none of these components of this entity can have
        changed: where it lives (table, row, layout) and the last write tick of each column.
        Ticks belong to tables, not rows, so a write to another entity of the same table changes
        the stamp too (never the reverse). For caching what is derived from one entity."""
        table, row = self._locate(int(eid))
        keys = self._stamp_keys.get(component_types)
        if keys is None:
            keys = self._stamp_keys[component_types] = [
                (ct, name) for ct in map(schema_of, component_types) for name in ct.__fields__]
        ticks = table.column_ticks
        try:
            return (table.id, table.version, row, *[ticks[k] for k in keys])
        except KeyError:
            missing = next(ct for ct in map(schema_of, component_types) if not table.has(ct))
            raise MissingComponentError(f"{describe_entity(int(eid))} has no {missing.__name__}") from None

    # ----------------------------------------------------------------- ticks
    def _write_tick(self) -> int:
        if self._system is not None:
            return self._system_tick
        self.tick += 1
        return self.tick

    def system_last_run_tick(self) -> int:
        if self._system is None:
            raise EcsError("a `changed` filter outside a system needs an explicit since=tick")
        return self._system.last_run_tick

    # ---------------------------------------------------------------- tables
    def _table_for(self, types: frozenset[type[Component]]) -> ArchetypeTable:
        tid = self._table_ids.get(types)
        if tid is not None:
            return self._tables[tid]
        ordered = tuple(sorted(types, key=lambda t: t.component_id))
        table = ArchetypeTable(len(self._tables), ordered)
        self._tables.append(table)
        self._table_ids[types] = table.id
        return table

    def _with(self, table: ArchetypeTable, ct: type[Component]) -> ArchetypeTable:
        tid = table.add_edges.get(ct)
        if tid is None:
            dst = self._table_for(frozenset(closure(set(table.type_set) | {ct})))
            table.add_edges[ct] = dst.id
            return dst
        return self._tables[tid]

    def _without(self, table: ArchetypeTable, ct: type[Component]) -> ArchetypeTable:
        tid = table.remove_edges.get(ct)
        if tid is None:
            needs = [t.__name__ for t in table.types if ct in t.required]
            if needs:
                raise EcsError(f"cannot remove {ct.__name__}: {', '.join(needs)} requires it")
            dst = self._table_for(table.type_set - {ct})
            table.remove_edges[ct] = dst.id
            return dst
        return self._tables[tid]

    # ------------------------------------------------------------ checking
    def _bundles(self, values: Iterable[Any], n: int, who: Any) -> Checked:
        checked: Checked = {}
        for value in values:
            if isinstance(value, type):
                raise TypeError(
                    f"pass a component value such as {value.__name__}(), not the class itself"
                )
            if isinstance(value, Component):
                ct = type(value)
            else:
                if n != 1:
                    raise TypeError(
                        f"{type(value).__name__} is a plain Python object: spawn_batch needs "
                        "Component schemas (plain objects can be spawned one at a time)"
                    )
                ct = object_component(type(value))
                value = ct(value=value)
            if ct in checked:
                raise ValueError(f"{ct.__name__} given twice")
            vals = {name: f.coerce(getattr(value, name), n, who) for name, f in ct.__fields__.items()}
            ct.check(vals, who)
            checked[ct] = vals
        return checked

    def _ids(self, target: Any, allow_reserved: bool = False) -> np.ndarray:
        """Validated, duplicate-free int64 ids; raises DeadEntityError naming the first bad id."""
        ids = np.asarray(target)
        if ids.dtype.kind not in "iu":
            raise TypeError(f"entity ids must be integers, got {ids.dtype}")
        ids = ids.astype(np.int64, copy=False).reshape(-1)
        ok = self._index.valid(ids)
        if not allow_reserved:
            ok &= self._index.table[np.where(ok, ids & INDEX_MASK, 0)] >= 0
        if not ok.all():
            bad = int(ids[~ok][0])
            raise DeadEntityError(self._dead_message(bad))
        if len(ids) > 1 and len(np.unique(ids)) != len(ids):
            raise ValueError("the same entity id appears more than once")
        if self._pending_destroy and np.isin(ids, list(self._pending_destroy)).any():
            bad = int(ids[np.isin(ids, list(self._pending_destroy))][0])
            raise DeadEntityError(f"{describe_entity(bad)} is already queued for destruction")
        return ids

    def _dead_message(self, eid: int) -> str:
        if self._index.valid_one(eid) and int(self._index.table[eid & INDEX_MASK]) == RESERVED:
            return f"{describe_entity(eid)} is spawned at the next sync point; it cannot be read yet"
        return f"{describe_entity(eid)} is not alive (destroyed, or never created)"

    def _locate(self, eid: int) -> tuple[ArchetypeTable, int]:
        index = eid & INDEX_MASK
        if not self._index.valid_one(eid) or int(self._index.table[index]) < 0:
            raise DeadEntityError(self._dead_message(eid))
        return self._tables[int(self._index.table[index])], int(self._index.row[index])

    def _check_write_access(self, ct: type[Component]) -> None:
        system = self._system
        if system is not None and system.writes is not None and ct not in system.writes:
            raise AccessError(f"system {system.name} writes {ct.__name__} but does not declare it")

    # ----------------------------------------------------------------- spawn
    def spawn(self, *values: Any) -> int:
        """Create one entity from component values; returns its id."""
        checked = self._bundles(values, 1, _new_entity)
        types = self._closure(checked)
        eid = self._index.allocate_one()
        if self.deferring:
            self._index.table[eid & INDEX_MASK] = RESERVED
            self._commands.append(("spawn", np.array([eid], dtype=np.int64), types, checked))
        else:
            self._place_one(eid, types, checked)
        return eid

    def _closure(self, checked: Checked) -> frozenset[type[Component]]:
        key = frozenset(checked)
        types = self._closures.get(key)
        if types is None:
            types = self._closures[key] = frozenset(closure(set(key)))
        return types

    def spawn_batch(self, n: int, *values: Component) -> np.ndarray:
        """Create n entities in one call; field values may be shared or given per row."""
        n = int(n)
        if n < 0:
            raise ValueError(f"cannot spawn a negative number of entities ({n})")
        checked = self._bundles(values, n, _new_entity)
        types = self._closure(checked)
        ids = self._index.allocate(n)
        if self.deferring:
            self._index.table[ids & INDEX_MASK] = RESERVED
            self._commands.append(("spawn", ids, types, checked))
        else:
            self._place(ids, types, checked)
        return ids

    def _place_one(self, eid: int, types: frozenset[type[Component]], checked: Checked) -> None:
        table = self._table_for(types)
        tick = self._write_tick()
        self.structure_version += 1
        row = table.push_one(eid, tick)
        columns = table.columns
        for key, f in table.fields.items():
            vals = checked.get(key[0])
            columns[key][row] = vals[key[1]][0] if vals is not None else f.default
        index = eid & INDEX_MASK
        self._index.table[index] = table.id
        self._index.row[index] = row

    def _place(self, ids: np.ndarray, types: frozenset[type[Component]], checked: Checked) -> None:
        table = self._table_for(types)
        tick = self._write_tick()
        self.structure_version += 1
        rows = table.push(ids, tick)
        given = {(ct, name) for ct, vals in checked.items() for name in vals}
        table.fill_defaults(rows, exclude=given)
        for ct, vals in checked.items():
            for name, arr in vals.items():
                table.columns[(ct, name)][rows] = arr
        index = ids & INDEX_MASK
        self._index.table[index] = table.id
        self._index.row[index] = np.arange(rows.start, rows.stop)

    # --------------------------------------------------------------- destroy
    def destroy(self, target: Any) -> None:
        """Destroy one entity or an array of them. Their ids never name an entity again."""
        if isinstance(target, (int, np.integer)) and not self.deferring:
            self._destroy_one(int(target))
            return
        ids = self._ids(target, allow_reserved=self.deferring)
        if self.deferring:
            self._pending_destroy.update(ids.tolist())
            self._commands.append(("destroy", ids))
            return
        self._destroy_now(ids)

    def _destroy_one(self, eid: int) -> None:
        table, row = self._locate(eid)
        self.structure_version += 1
        moved = table.remove_row(row)
        if moved:
            self._index.row[moved & INDEX_MASK] = row
        self._index.release_one(eid & INDEX_MASK)

    def _destroy_now(self, ids: np.ndarray) -> None:
        if len(ids) == 1:
            self._destroy_one(int(ids[0]))
            return
        index = ids & INDEX_MASK
        self.structure_version += 1
        tables = self._index.table[index]
        rows = self._index.row[index]
        for tid in np.unique(tables):
            sel = tables == tid
            moved, new_rows = self._tables[tid].remove_rows(rows[sel])
            self._index.row[moved & INDEX_MASK] = new_rows
        self._index.release(index)

    # ------------------------------------------------------------ add/remove
    def add(self, target: Any, value: Any) -> None:
        """Add a component to one entity or many (rows move tables). An existing one is replaced."""
        ids = self._ids(target, allow_reserved=self.deferring)
        checked = self._bundles([value], 1 if len(ids) == 1 else len(ids), self._who(ids))
        ((ct, vals),) = checked.items()
        if self.deferring:
            self._commands.append(("add", ids, ct, vals))
            return
        self._add_now(ids, ct, vals)

    def _add_now(self, ids: np.ndarray, ct: type[Component], vals: dict[str, np.ndarray]) -> None:
        tick = self._write_tick()
        for src, rows, sel in self._groups(ids):
            sub = _select(vals, sel, len(ids))
            if src.has(ct):
                src.write(rows, ct, sub, tick)
                continue
            dst = self._with(src, ct)
            dst_rows = self._move(src, dst, rows, ids[sel] if sel is not None else ids, tick)
            dst.write(dst_rows, ct, sub, tick)

    def remove(self, target: Any, component_type: type) -> None:
        """Remove a component from one entity or many; raises if one of them lacks it."""
        ct = schema_of(component_type)
        ids = self._ids(target, allow_reserved=self.deferring)
        if self.deferring:
            self._commands.append(("remove", ids, ct))
            return
        self._remove_now(ids, ct, strict=True)

    def _remove_now(self, ids: np.ndarray, ct: type[Component], strict: bool) -> None:
        groups = list(self._groups(ids))
        if strict:
            for src, rows, _ in groups:
                if not src.has(ct):
                    eid = int(src.entities[rows[0]])
                    raise MissingComponentError(f"{describe_entity(eid)} has no {ct.__name__} to remove")
        targets = [(src, self._without(src, ct), rows, sel) for src, rows, sel in groups if src.has(ct)]
        tick = self._write_tick()
        for src, dst, rows, sel in targets:
            self._move(src, dst, rows, ids[sel] if sel is not None else ids, tick)

    def _groups(self, ids: np.ndarray) -> Iterator[tuple[ArchetypeTable, np.ndarray, np.ndarray | None]]:
        """(table, rows, selector into ids) for each table holding some of `ids`."""
        index = ids & INDEX_MASK
        tables = self._index.table[index]
        rows = self._index.row[index]
        if len(ids) == 1 or (tables == tables[0]).all():
            yield self._tables[int(tables[0])], rows, None
            return
        for tid in np.unique(tables):
            sel = tables == tid
            yield self._tables[tid], rows[sel], sel

    def _move(self, src: ArchetypeTable, dst: ArchetypeTable, rows: np.ndarray, ids: np.ndarray, tick: int) -> slice:
        """Copy rows to `dst` (new columns get defaults), swap-remove them from `src`."""
        self.structure_version += 1
        dst_rows = dst.push(ids, tick)
        for key, col in dst.columns.items():
            source = src.columns.get(key)
            if source is not None:
                col[dst_rows] = source[rows]
            else:
                col[dst_rows] = dst.fields[key].default
        if len(rows) == 1:
            moved = src.remove_row(int(rows[0]))
            if moved:
                self._index.row[moved & INDEX_MASK] = rows[0]
        else:
            moved_ids, new_rows = src.remove_rows(rows)
            self._index.row[moved_ids & INDEX_MASK] = new_rows
        index = ids & INDEX_MASK
        self._index.table[index] = dst.id
        self._index.row[index] = np.arange(dst_rows.start, dst_rows.stop)
        return dst_rows

    # --------------------------------------------------------------- get/set
    def get(self, eid: int, component_type: type) -> Any:
        """A copy of one entity's component (for a plain Python class: the stored object)."""
        eid = int(eid)
        ct = schema_of(component_type)
        table, row = self._locate(eid)
        if not table.has(ct):
            raise MissingComponentError(f"{describe_entity(eid)} has no {ct.__name__}")
        if issubclass(ct, ObjectStore):
            return table.columns[(ct, "value")][row]
        out = ct.__new__(ct)
        for name, f in ct.__fields__.items():
            v = table.columns[(ct, name)][row]
            setattr(out, name, v.copy() if f.shape else v.item())
        return out

    def set(self, target: Any, value: Any, /, **fields: Any) -> None:
        """Overwrite a component of one entity or many.

        `set(e, Transform(...))` replaces every field; `set(e, Transform, position=p)` only the
        named ones. The entities must already have the component.
        """
        if isinstance(value, type):
            ct = schema_of(value)
            if not fields:
                raise TypeError(f"set({ct.__name__}, ...) needs field=value arguments")
            unknown = set(fields) - set(ct.__fields__)
            if unknown:
                raise TypeError(f"{ct.__name__} has no field(s) {sorted(unknown)}")
            raw = fields
        else:
            if fields:
                raise TypeError("give either a component value or a type with field=value arguments")
            if isinstance(value, Component):
                ct = type(value)
                raw = value.values()
            else:
                ct = object_component(type(value))
                raw = {"value": value}
        self._check_write_access(ct)
        ids = self._ids(target, allow_reserved=self.deferring)
        n = len(ids)
        who = self._who(ids)
        vals = {name: ct.__fields__[name].coerce(v, n, who) for name, v in raw.items()}
        placed = self._index.table[ids & INDEX_MASK] >= 0
        if len(vals) < len(ct.__fields__) and placed.all() and self._all_have(ids, ct):
            # partial write: cross-field checks see the stored values of the other fields
            ct.check({**self._stored(ids, ct), **vals}, who)
        elif len(vals) == len(ct.__fields__):
            ct.check(vals, who)
        if self.deferring and (not placed.all() or not self._all_have(ids, ct)):
            self._commands.append(("set", ids, ct, vals))
            return
        self._set_now(ids, ct, vals)

    def _stored(self, ids: np.ndarray, ct: type[Component]) -> dict[str, np.ndarray]:
        index = ids & INDEX_MASK
        out = {}
        for name in ct.__fields__:
            out[name] = np.stack([
                self._tables[int(t)].columns[(ct, name)][int(r)]
                for t, r in zip(self._index.table[index], self._index.row[index])
            ])
        return out

    def _all_have(self, ids: np.ndarray, ct: type[Component]) -> bool:
        return all(src.has(ct) for src, _, _ in self._groups(ids))

    def _set_now(self, ids: np.ndarray, ct: type[Component], vals: dict[str, np.ndarray]) -> None:
        groups = list(self._groups(ids))
        for src, rows, _ in groups:
            if not src.has(ct):
                eid = int(src.entities[rows[0]])
                raise MissingComponentError(f"{describe_entity(eid)} has no {ct.__name__}")
        tick = self._write_tick()
        for src, rows, sel in groups:
            src.write(rows, ct, _select(vals, sel, len(ids)), tick)

    def _who(self, ids: np.ndarray) -> Any:
        return lambda row: describe_entity(int(ids[row]))

    # --------------------------------------------------------------- queries
    def query(
        self,
        *required: type,
        with_: Iterable[type] = (),
        without: Iterable[type] = (),
        write: Iterable[type] | None = None,
    ) -> Query:
        """A cached query. `write` defaults to every required type outside a system and to the
        system's declared writes inside one; other columns come back read-only."""
        system = self._system
        fast = None
        if type(with_) is tuple and type(without) is tuple and (write is None or type(write) is tuple):
            # the same call from the same place every frame: skip resolving and checking again
            fast = (required, with_, without, write, system,
                    None if system is None else (system.reads, system.writes))
            q = self._queries_by_call.get(fast)
            if q is not None:
                return q
        req = tuple(schema_of(t) for t in required)
        w_set = frozenset(schema_of(t) for t in with_)
        wo_set = frozenset(schema_of(t) for t in without)
        if write is None:
            writes = frozenset(req)
            if system is not None and system.writes is not None:
                writes &= system.writes
        else:
            writes = frozenset(schema_of(t) for t in write)
            extra = writes - set(req)
            if extra:
                raise ValueError(f"write={sorted(t.__name__ for t in extra)} must also be queried")
        if system is not None and system.writes is not None:
            check_access(system.name, system.reads, system.writes, req, writes)
        key = (req, w_set, wo_set, writes)
        q = self._queries.get(key)
        if q is None:
            q = self._queries[key] = Query(self, req, w_set, wo_set, writes)
        if fast is not None:
            self._queries_by_call[fast] = q
        return q

    def _begin_iteration(self) -> None:
        self._iter_depth += 1

    def _end_iteration(self) -> None:
        self._iter_depth -= 1
        if not self.deferring and self._commands:
            self.flush()

    # ------------------------------------------------------------ deferral
    @contextmanager
    def deferred(self) -> Iterator[World]:
        """Queue structural changes made inside the block; apply them when it ends."""
        self._defer_depth += 1
        try:
            yield self
        finally:
            self._defer_depth -= 1
            if not self.deferring and self._commands:
                self.flush()

    def flush(self) -> None:
        """Sync point: apply queued structural changes in the order they were requested.

        A queued `remove` of a component the entity no longer has is skipped; any other
        failing command is reported after all the others were applied.
        """
        if self._iter_depth or self._system is not None:
            raise EcsError("flush() cannot run while a system or a query loop is active")
        commands, self._commands = self._commands, []
        self._pending_destroy.clear()
        errors: list[Exception] = []
        for cmd in commands:
            try:
                kind = cmd[0]
                if kind == "spawn":
                    self._place(cmd[1], cmd[2], cmd[3])
                elif kind == "destroy":
                    self._destroy_now(cmd[1])
                elif kind == "add":
                    self._add_now(cmd[1], cmd[2], cmd[3])
                elif kind == "remove":
                    self._remove_now(cmd[1], cmd[2], strict=False)
                else:
                    self._set_now(cmd[1], cmd[2], cmd[3])
            except EcsError as exc:
                errors.append(exc)
        if errors:
            more = f" (and {len(errors) - 1} more failed commands)" if len(errors) > 1 else ""
            raise type(errors[0])(f"{errors[0]}{more}")

    # ---------------------------------------------------------------- systems
    def run_system(self, system: System, dt: float) -> None:
        """Run one system with its own change tick; structural changes wait for a flush."""
        if self._system is not None:
            raise EcsError(f"system {system.name} started inside system {self._system.name}")
        self.tick += 1
        tick = self.tick
        self._system = system
        self._system_tick = tick
        try:
            system.run(self, dt)
        finally:
            self._system = None
            system.last_run_tick = tick


def _select(vals: dict[str, np.ndarray], sel: np.ndarray | None, n: int) -> dict[str, np.ndarray]:
    """The rows of per-entity value arrays picked by `sel`; shared values pass unchanged."""
    if sel is None:
        return vals
    return {name: arr[sel] if arr.shape[0] == n and n > 1 else arr for name, arr in vals.items()}
