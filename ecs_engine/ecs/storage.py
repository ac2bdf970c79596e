"""Where entities live: the entity index, the archetype tables and the graph between them, and
the structural operations on values that were already checked.

Kept apart from `World` (as Bevy keeps its archetype metadata and storages apart from the world
facade): the world checks input, defers while systems iterate and hands out queries; the
storage only moves rows. Every operation here takes the change tick to stamp on the columns it
writes, so it never needs to know which system is running.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from .entities import INDEX_MASK, RESERVED, EntityIndex
from .errors import DeadEntityError, EcsError, MissingComponentError, describe_entity
from .lifecycle import LifecycleLog
from .schema import Component, closure
from .table import ArchetypeTable

# per component type: field name -> values, shape (1, ...) (shared) or (n, ...) (per row)
Checked = dict[type[Component], dict[str, np.ndarray]]
Values = dict[str, np.ndarray]


class Storage:
    def __init__(self) -> None:
        self.index = EntityIndex()
        self.tables: list[ArchetypeTable] = []  # a query keeps this list and scans what is new
        self._table_ids: dict[frozenset[type[Component]], int] = {}
        # Bumped by every spawn, destroy, add and remove that is applied (not when queued).
        self.structure_version = 0
        # {name: answer}: ecs/structural.py's answers for this structure (a new dict at each bump)
        self.answers: dict[Any, Any] = {}
        self._places: dict[int, tuple[int, ArchetypeTable, int]] = {}  # see located
        self.log: LifecycleLog | None = None  # made when something watches components come and go
        self.table_for(frozenset())

    # ----------------------------------------------------------------- tables
    def table_for(self, types: frozenset[type[Component]]) -> ArchetypeTable:
        tid = self._table_ids.get(types)
        if tid is not None:
            return self.tables[tid]
        ordered = tuple(sorted(types, key=lambda t: t.component_id))
        table = ArchetypeTable(len(self.tables), ordered)
        self.tables.append(table)
        self._table_ids[types] = table.id
        return table

    def _with(self, table: ArchetypeTable, ct: type[Component]) -> ArchetypeTable:
        tid = table.add_edges.get(ct)
        if tid is None:
            dst = self.table_for(frozenset(closure(set(table.type_set) | {ct})))
            table.add_edges[ct] = dst.id
            return dst
        return self.tables[tid]

    def _without(self, table: ArchetypeTable, ct: type[Component]) -> ArchetypeTable:
        tid = table.remove_edges.get(ct)
        if tid is None:
            needs = [t.__name__ for t in table.types if ct in t.required]
            if needs:
                raise EcsError(f"cannot remove {ct.__name__}: {', '.join(needs)} requires it")
            dst = self.table_for(table.type_set - {ct})
            table.remove_edges[ct] = dst.id
            return dst
        return self.tables[tid]

    # ----------------------------------------------------------------- lookup
    def locate(self, eid: int) -> tuple[ArchetypeTable, int]:
        """The table and row of a live, placed entity; DeadEntityError otherwise."""
        index = eid & INDEX_MASK
        if not self.index.valid_one(eid) or int(self.index.table[index]) < 0:
            raise DeadEntityError(self.dead_message(eid))
        return self.tables[int(self.index.table[index])], int(self.index.row[index])

    def located(self, eid: int) -> tuple[ArchetypeTable, int]:
        """`locate`, the answer kept until the next structural change: for what is asked of the
        same entity every frame (the camera's change stamp), where the index reads cost ~1 us."""
        found = self._places.get(eid)
        if found is not None and found[0] == self.structure_version:
            return found[1], found[2]
        table, row = self.locate(eid)
        if len(self._places) >= 64:
            self._places.clear()
        self._places[eid] = (self.structure_version, table, row)
        return table, row

    def dead_message(self, eid: int) -> str:
        if self.index.valid_one(eid) and int(self.index.table[eid & INDEX_MASK]) == RESERVED:
            return f"{describe_entity(eid)} is spawned at the next sync point; it cannot be read yet"
        return f"{describe_entity(eid)} is not alive (destroyed, or never created)"

    def placed(self, ids: np.ndarray) -> np.ndarray:
        """Mask of ids (already valid) that sit in a table, not waiting for a deferred spawn."""
        return self.index.table[ids & INDEX_MASK] >= 0

    def groups(self, ids: np.ndarray) -> Iterator[tuple[ArchetypeTable, np.ndarray, np.ndarray | None]]:
        """(table, rows, selector into ids) for each table holding some of `ids`."""
        index = ids & INDEX_MASK
        tables = self.index.table[index]
        rows = self.index.row[index]
        if len(ids) == 1 or (tables == tables[0]).all():
            yield self.tables[int(tables[0])], rows, None
            return
        for tid in np.unique(tables):
            sel = tables == tid
            yield self.tables[tid], rows[sel], sel

    def all_have(self, ids: np.ndarray, ct: type[Component]) -> bool:
        return all(src.has(ct) for src, _, _ in self.groups(ids))

    def stored(self, ids: np.ndarray, ct: type[Component]) -> Values:
        """The current values of `ct` for placed entities that all have it, one row each."""
        index = ids & INDEX_MASK
        return {
            name: np.stack(
                [
                    self.tables[int(t)].columns[(ct, name)][int(r)]
                    for t, r in zip(self.index.table[index], self.index.row[index])
                ]
            )
            for name in ct.__fields__
        }

    def _restructured(self) -> None:
        """A spawn, destroy, add or remove is applied: a new structure version, no answers kept."""
        self.structure_version += 1
        self.answers = {}

    # ------------------------------------------------------------------ spawn
    def place_one(self, eid: int, types: frozenset[type[Component]], checked: Checked, tick: int) -> None:
        table = self.table_for(types)
        self._restructured()
        row = table.push_one(eid, tick)
        columns = table.columns
        for key, f in table.fields.items():
            vals = checked.get(key[0])
            columns[key][row] = vals[key[1]][0] if vals is not None else f.default
        index = eid & INDEX_MASK
        self.index.table[index] = table.id
        self.index.row[index] = row
        if self.log is not None:
            self.log.placed(types, np.array([eid], np.int64))

    def place(self, ids: np.ndarray, types: frozenset[type[Component]], checked: Checked, tick: int) -> None:
        table = self.table_for(types)
        self._restructured()
        rows = table.push(ids, tick)
        given = {(ct, name) for ct, vals in checked.items() for name in vals}
        table.fill_defaults(rows, exclude=given)
        for ct, vals in checked.items():
            for name, arr in vals.items():
                table.columns[(ct, name)][rows] = arr
        index = ids & INDEX_MASK
        self.index.table[index] = table.id
        self.index.row[index] = np.arange(rows.start, rows.stop)
        if self.log is not None:
            self.log.placed(types, ids)

    # ---------------------------------------------------------------- destroy
    def destroy_one(self, eid: int) -> None:
        table, row = self.locate(eid)
        if self.log is not None:
            self.log.destroyed(table, np.array([row]), np.array([eid], np.int64))
        self._restructured()
        moved = table.remove_row(row)
        if moved:
            self.index.row[moved & INDEX_MASK] = row
        self.index.release_one(eid & INDEX_MASK)

    def destroy(self, ids: np.ndarray) -> None:
        if len(ids) == 1:
            self.destroy_one(int(ids[0]))
            return
        index = ids & INDEX_MASK
        self._restructured()
        tables = self.index.table[index]
        rows = self.index.row[index]
        for tid in np.unique(tables):
            sel = tables == tid
            if self.log is not None:
                self.log.destroyed(self.tables[tid], rows[sel], ids[sel])
            moved, new_rows = self.tables[tid].remove_rows(rows[sel])
            self.index.row[moved & INDEX_MASK] = new_rows
        self.index.release(index)

    # ------------------------------------------------------------- add/remove
    def add(self, ids: np.ndarray, ct: type[Component], vals: Values, tick: int) -> None:
        """Give `ids` the component (moving rows to the table with it), or overwrite it."""
        for src, rows, sel in self.groups(ids):
            sub = select_rows(vals, sel, len(ids))
            if src.has(ct):
                src.write(rows, ct, sub, tick)
                continue
            dst = self._with(src, ct)
            dst_rows = self._move(src, dst, rows, ids[sel] if sel is not None else ids, tick)
            dst.write(dst_rows, ct, sub, tick)

    def remove(self, ids: np.ndarray, ct: type[Component], strict: bool, tick: int) -> None:
        """Take the component from `ids`; with `strict`, every one of them must have it."""
        groups = list(self.groups(ids))
        if strict:
            for src, rows, _ in groups:
                if not src.has(ct):
                    eid = int(src.entities[rows[0]])
                    raise MissingComponentError(f"{describe_entity(eid)} has no {ct.__name__} to remove")
        targets = [(src, self._without(src, ct), rows, sel) for src, rows, sel in groups if src.has(ct)]
        for src, dst, rows, sel in targets:
            self._move(src, dst, rows, ids[sel] if sel is not None else ids, tick)

    def write(self, ids: np.ndarray, ct: type[Component], vals: Values, tick: int) -> None:
        """Overwrite fields of a component every one of `ids` has."""
        groups = list(self.groups(ids))
        for src, rows, _ in groups:
            if not src.has(ct):
                eid = int(src.entities[rows[0]])
                raise MissingComponentError(f"{describe_entity(eid)} has no {ct.__name__}")
        for src, rows, sel in groups:
            src.write(rows, ct, select_rows(vals, sel, len(ids)), tick)

    def _move(self, src: ArchetypeTable, dst: ArchetypeTable, rows: np.ndarray, ids: np.ndarray, tick: int) -> slice:
        """Copy rows to `dst` (new columns get defaults), swap-remove them from `src`."""
        if self.log is not None:
            self.log.moved(src, dst, rows, ids)
        self._restructured()
        dst_rows = dst.push(ids, tick)
        for key, col in dst.columns.items():
            source = src.columns.get(key)
            if source is not None:
                col[dst_rows] = source[rows]
            else:
                col[dst_rows] = dst.fields[key].fill_value
        if len(rows) == 1:
            moved = src.remove_row(int(rows[0]))
            if moved:
                self.index.row[moved & INDEX_MASK] = rows[0]
        else:
            moved_ids, new_rows = src.remove_rows(rows)
            self.index.row[moved_ids & INDEX_MASK] = new_rows
        index = ids & INDEX_MASK
        self.index.table[index] = dst.id
        self.index.row[index] = np.arange(dst_rows.start, dst_rows.stop)
        return dst_rows

    # ----------------------------------------------------------------- memory
    def nbytes(self) -> int:
        return self.index.nbytes() + sum(t.nbytes() for t in self.tables)

    def shrink_to_fit(self) -> None:
        for t in self.tables:
            t.shrink_to_fit()
        self.index.shrink_to_fit()


def select_rows(vals: Values, sel: np.ndarray | None, n: int) -> Values:
    """The rows of per-entity value arrays picked by `sel`; shared values pass unchanged."""
    if sel is None:
        return vals
    return {name: arr[sel] if arr.shape[0] == n and n > 1 else arr for name, arr in vals.items()}
