"""Observers: a function run with the batch of entities that gained, lost or changed a component
(Bevy's observers and component hooks, in bulk).

    def give_bars(world, trigger):  # trigger.entities: the int64 ids, all at once
        world.add(trigger.entities, HealthBar())

    world.add_observer(OnAdd(Health), give_bars)
    world.add_observer(OnRemove(Body), lambda world, t: physics.free(t.values.handle))

When: at the sync point where the structural changes are applied (after each schedule stage, at
the end of a query loop or `world.deferred()` block, or at once for a change made outside
them), once the whole queue is applied. Each observer runs once per sync point, in the order
they were added, with everything it watches that happened there, in the order it was applied:
- `OnAdd(C)`: entities that gained C (spawned with it, or C added); one that lost it again
  before the observers ran is left out (it shows in OnRemove, with its values).
- `OnRemove(C)`: entities that lost C (removed, or destroyed with it); `trigger.values` holds
  the component's fields as they were (one row per entity): the component is gone by now.
- `OnChange(C)`: entities whose C may have changed since the observer last ran. Change ticks
  belong to tables, not rows (query.py), so this is every entity of each table where a C column
  was written (through a query, `set`, or rows moved in): a superset of the ones written, found
  for the price of one tick test per table.
An observer runs as a system (its own change tick; its structural changes are deferred and
applied right after the observers of that sync point, which may trigger more of them, up to
`MAX_ROUNDS`), so a parallel schedule's results do not depend on threads: the changes it
reports were applied in declared order. Declare `reads`/`writes` to have its access checked.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .events import Columns
from .lifecycle import Change, Kind
from .schema import Component, schema_of

MAX_ROUNDS = 64  # observer rounds at one sync point before a loop is reported


class ObserverTrigger:
    """What an observer watches: a kind of change of one component type."""

    kind: str = ""

    def __init__(self, component: type) -> None:
        if not isinstance(component, type):
            raise TypeError(f"{type(self).__name__} takes a component type (a class), got {component!r}")
        self.component = schema_of(component)
        self.name = component.__name__

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name})"


class OnAdd(ObserverTrigger):
    """Entities gained the component (spawned with it, or it was added)."""

    kind = "add"


class OnRemove(ObserverTrigger):
    """Entities lost the component (removed, or destroyed with it); the trigger has its values."""

    kind = "remove"


class OnChange(ObserverTrigger):
    """The component may have changed (by table: see the module)."""

    kind = "change"


@dataclass(frozen=True)
class Trigger:
    """What an observer is called with."""

    kind: str  # "add", "remove" or "change"
    component: type[Component]
    entities: np.ndarray  # int64 ids
    values: Columns | None = None  # OnRemove: the fields as they were, `values.hp[i]` for entities[i]

    def __len__(self) -> int:
        return len(self.entities)


ObserverFunction = Callable[[Any, Trigger], Any]


class Observer:
    """A registered observer (`World.add_observer` returns it; `remove_observer` takes it)."""

    def __init__(
        self,
        trigger: ObserverTrigger,
        fn: ObserverFunction,
        name: str | None = None,
        reads: Iterable[type] | None = None,
        writes: Iterable[type] | None = None,
    ) -> None:
        if not isinstance(trigger, ObserverTrigger):
            raise TypeError(f"an observer watches OnAdd(C), OnRemove(C) or OnChange(C), got {trigger!r}")
        if not callable(fn):
            raise TypeError(f"an observer is a function of (world, trigger), got {fn!r}")
        self.trigger = trigger
        self.fn = fn
        self.name = str(name or getattr(fn, "__name__", "observer"))
        declared = reads is not None or writes is not None  # else it may touch anything (it runs alone)
        self.reads = frozenset(schema_of(t) for t in reads or ()) if declared else None
        self.writes = frozenset(schema_of(t) for t in writes or ()) if declared else None
        self.last_run_tick = 0
        self.pending: Trigger | None = None  # what the next run gets

    def run(self, world: Any, dt: float) -> None:
        trigger, self.pending = self.pending, None
        assert trigger is not None
        self.fn(world, trigger)

    def __repr__(self) -> str:
        return f"<observer {self.name} on {self.trigger!r}>"


def structural_trigger(
    observer: Observer, changes: list[Change], holding: Callable[[np.ndarray, type[Component]], np.ndarray]
) -> Trigger | None:
    """The batch of `changes` for an OnAdd or OnRemove observer (None: nothing for it);
    `holding(ids, C)`: which of the ids name live entities that have C."""
    kind: Kind = "add" if observer.trigger.kind == "add" else "remove"
    ct = observer.trigger.component
    mine = [c for c in changes if c.kind == kind and c.component is ct]
    if not mine:
        return None
    ids = mine[0].entities if len(mine) == 1 else np.concatenate([c.entities for c in mine])
    if kind == "add":
        ids = _first_each(ids)
        ids = ids[holding(ids, ct)]  # gained and lost again: only in the removals
        return Trigger(kind, ct, ids) if len(ids) else None
    values = None
    kept = [c.values for c in mine if c.values is not None]
    if len(kept) == len(mine):
        arrays = {name: np.concatenate([v[name] for v in kept]) for name in ct.__fields__}
        for array in arrays.values():
            array.flags.writeable = False
        values = Columns(ct, arrays, len(ids))
    return Trigger(kind, ct, ids, values)


def _first_each(ids: np.ndarray) -> np.ndarray:
    """`ids` without repeats, in the order each first appears."""
    if len(ids) < 2:
        return ids
    _, first = np.unique(ids, return_index=True)
    return ids if len(first) == len(ids) else ids[np.sort(first)]
