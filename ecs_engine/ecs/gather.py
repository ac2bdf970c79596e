"""One field of many entities at once, by id: what a system that follows references (a skin's
joints, a constraint's bodies) reads in bulk instead of calling World.get per entity."""

from __future__ import annotations

from typing import Any

import numpy as np

from .entities import INDEX_MASK


def gather(world: Any, ids: np.ndarray, component: type, field: str, fill: Any = 0) -> tuple[np.ndarray, np.ndarray]:
    """(values, found): `component.field` of each entity of `ids` (any shape), and whether it was
    there; an id that is dead, or whose entity lacks the component, gets `fill`. Reads the tables'
    columns directly: a system calling it declares `component` among its reads."""
    ids = np.asarray(ids, np.int64)
    flat = ids.reshape(-1)
    found = world.alive(flat)
    index = world.storage.index
    at = np.where(found, flat & INDEX_MASK, 0)
    tables, rows = index.table[at], index.row[at]
    key = (component, field)
    shape: tuple[int, ...] | None = None
    out: np.ndarray | None = None
    for tid in np.unique(tables[found]).tolist():
        column = world.storage.tables[tid].columns.get(key)
        mine = found & (tables == tid)
        if column is None:
            found &= ~mine
            continue
        if out is None:
            shape = column.shape[1:]
            out = np.full((len(flat), *shape), fill, column.dtype)
        out[mine] = column[rows[mine]]
    if out is None:  # nothing found: the field's shape and type from its declaration
        declared = component.__fields__[field]  # type: ignore[attr-defined]
        out = np.full((len(flat), *declared.shape), fill, declared.dtype)
    assert shape is None or out.shape[1:] == shape
    return out.reshape(*ids.shape, *out.shape[1:]), found.reshape(ids.shape)
