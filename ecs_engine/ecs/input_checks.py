"""What enters the world through its API, checked: entity ids and component values. A failed
check raises before anything changes, naming the argument, the entity or the row at fault."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from .entities import INDEX_MASK
from .errors import DeadEntityError, describe_entity
from .schema import Component, object_component, refuse_non_component
from .storage import Checked, Storage


def entity_id(eid: Any) -> int:
    """One entity id as a Python int; integers only (one rule for every call that takes one)."""
    if isinstance(eid, (int, np.integer)) and not isinstance(eid, (bool, np.bool_)):
        return int(eid)
    raise TypeError(f"entity ids must be integers, got {type(eid).__name__} {eid!r}")


def new_entity(row: int) -> str:
    """How errors name a row of a spawn."""
    return "new entity" if row == 0 else f"new entity (row {row} of the batch)"


def who_of(ids: np.ndarray) -> Callable[[int], str]:
    """How errors name a row of a call on existing entities."""
    return lambda row: describe_entity(int(ids[row]))


def checked_components(values: Iterable[Any], n: int, who: Any, call: str, first: int) -> Checked:
    """The checked values of the components given to `call` (named in errors) from its argument
    `first` on, for n entities."""
    checked: Checked = {}
    for position, value in enumerate(values, first):
        if isinstance(value, Component):
            ct = type(value)
        else:
            refuse_non_component(value, call, position)
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


def checked_ids(storage: Storage, target: Any, allow_reserved: bool, pending_destroy: set[int]) -> np.ndarray:
    """Validated, duplicate-free int64 ids of live entities (or ones waiting for their deferred
    spawn, with `allow_reserved`), none queued for destruction; DeadEntityError names the first
    bad one."""
    ids = np.asarray(target)
    if ids.dtype.kind not in "iu":
        raise TypeError(f"entity ids must be integers, got {ids.dtype}")
    ids = ids.astype(np.int64, copy=False).reshape(-1)
    index = storage.index
    ok = index.valid(ids)
    if not allow_reserved:
        ok &= index.table[np.where(ok, ids & INDEX_MASK, 0)] >= 0
    if not ok.all():
        bad = int(ids[~ok][0])
        raise DeadEntityError(storage.dead_message(bad))
    if len(ids) > 1 and len(np.unique(ids)) != len(ids):
        raise ValueError("the same entity id appears more than once")
    if pending_destroy and np.isin(ids, list(pending_destroy)).any():
        bad = int(ids[np.isin(ids, list(pending_destroy))][0])
        raise DeadEntityError(f"{describe_entity(bad)} is already queued for destruction")
    return ids
