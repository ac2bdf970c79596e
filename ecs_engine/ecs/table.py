"""Archetype tables: one per distinct set of component types, one NumPy column per field."""

from __future__ import annotations

from typing import Any

import numpy as np

from .schema import Component, Field

ColumnKey = tuple[type[Component], str]


class ArchetypeTable:
    """Rows are entities; columns are component fields. Grows by doubling, removes by swap.

    `entities[:count]` holds the ids of the rows. Column arrays are replaced when the table
    grows, so views handed out are valid until the next structural change (the world defers
    structural changes while systems and queries iterate, which keeps them valid there).
    """

    def __init__(self, table_id: int, types: tuple[type[Component], ...]) -> None:
        self.id = table_id
        self.types = types
        self.type_set = frozenset(types)
        self.count = 0
        self.capacity = 0
        # Bumped whenever rows are added or removed or arrays are replaced: views of an older
        # version may be stale.
        self.version = 0
        self.entities = np.empty(0, dtype=np.int64)
        self.fields: dict[ColumnKey, Field] = {(ct, name): f for ct in types for name, f in ct.__fields__.items()}
        self.object_keys = [key for key, f in self.fields.items() if f.is_object]
        self.columns: dict[ColumnKey, np.ndarray] = {
            key: np.empty((0, *f.shape), dtype=f.dtype) for key, f in self.fields.items()
        }
        # Change detection: world tick of the last write per column (adding rows counts as a
        # write; rows moved by swap-remove keep their values). Layout changes bump `version`.
        self.column_ticks: dict[ColumnKey, int] = dict.fromkeys(self.columns, 0)
        # Cached neighbour tables: component type -> table id with that type added/removed.
        self.add_edges: dict[type[Component], int] = {}
        self.remove_edges: dict[type[Component], int] = {}

    def __repr__(self) -> str:
        names = ", ".join(t.__name__ for t in self.types) or "<empty>"
        return f"ArchetypeTable#{self.id}[{names}] rows={self.count}"

    def has(self, ct: type[Component]) -> bool:
        return ct in self.type_set

    def nbytes(self) -> int:
        return self.entities.nbytes + sum(c.nbytes for c in self.columns.values())

    # ------------------------------------------------------------------ growth
    def reserve(self, extra: int) -> None:
        needed = self.count + extra
        if needed <= self.capacity:
            return
        new_cap = max(needed, 2 * self.capacity, 8)
        self.entities = _grow(self.entities, self.count, new_cap)
        for key, col in self.columns.items():
            self.columns[key] = _grow(col, self.count, new_cap)
        self.capacity = new_cap
        self.version += 1

    def shrink_to_fit(self) -> None:
        """Release spare capacity (growth by doubling can leave up to half a table unused)."""
        if self.capacity == self.count:
            return
        self.entities = self.entities[: self.count].copy()
        for key, col in self.columns.items():
            self.columns[key] = col[: self.count].copy()
        self.capacity = self.count
        self.version += 1

    # ------------------------------------------------------------------- rows
    def push(self, ids: np.ndarray, tick: int) -> slice:
        """Add len(ids) rows with unset columns; the caller fills them. Returns their slice."""
        n = len(ids)
        self.reserve(n)
        rows = slice(self.count, self.count + n)
        self.entities[rows] = ids
        self.count += n
        self._touch_all(tick)
        return rows

    def push_one(self, eid: int, tick: int) -> int:
        if self.count == self.capacity:
            self.reserve(1)
        row = self.count
        self.entities[row] = eid
        self.count = row + 1
        self._touch_all(tick)
        return row

    def fill_defaults(self, rows: slice, exclude: set[ColumnKey]) -> None:
        for key, f in self.fields.items():
            if key not in exclude:
                self.columns[key][rows] = f.fill_value

    def write(self, rows: Any, ct: type[Component], values: dict[str, np.ndarray], tick: int) -> None:
        for name, arr in values.items():
            self.columns[(ct, name)][rows] = arr
            self.column_ticks[(ct, name)] = tick

    def _touch_all(self, tick: int) -> None:
        self.version += 1
        for key in self.column_ticks:
            self.column_ticks[key] = tick

    def remove_rows(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Swap-remove `rows` (unique). Returns (ids of rows that moved, their new rows)."""
        n = self.count
        k = len(rows)
        new_n = n - k
        holes = np.sort(rows[rows < new_n])
        keep = np.ones(k, dtype=bool)
        keep[rows[rows >= new_n] - new_n] = False
        fillers = np.arange(new_n, n, dtype=np.int64)[keep]
        if len(holes):
            self.entities[holes] = self.entities[fillers]
            for col in self.columns.values():
                col[holes] = col[fillers]
        for key in self.object_keys:
            self.columns[key][new_n:n] = None  # drop references held past the end
        self.count = new_n
        self.version += 1
        return self.entities[holes], holes

    def remove_row(self, row: int) -> int:
        """Swap-remove one row. Returns the id that moved into it, or 0 if none moved."""
        last = self.count - 1
        moved = 0
        if row != last:
            moved = int(self.entities[last])
            self.entities[row] = moved
            for col in self.columns.values():
                col[row] = col[last]
        for key in self.object_keys:
            self.columns[key][last] = None
        self.count = last
        self.version += 1
        return moved


def _grow(arr: np.ndarray, count: int, new_cap: int) -> np.ndarray:
    out = np.empty((new_cap, *arr.shape[1:]), dtype=arr.dtype)
    out[:count] = arr[:count]
    return out
