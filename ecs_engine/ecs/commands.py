"""Structural changes requested while systems or query loops run: a typed command queue (as in
Bevy), applied in request order at the next sync point.

Each command holds values the world has already checked and applies itself to the storage, so
the queue needs no dispatch on a kind string and a new command is one small class. Each system
of a schedule stage queues on its own (the queues join in declared order), so a command may name
an entity that an earlier one of the same sync point destroyed: it leaves that entity out.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .entities import INDEX_MASK
from .errors import DeadEntityError, EcsError, describe_entity
from .schema import Component
from .storage import Checked, Storage, Values, select_rows

Tick = Callable[[], int]  # the change tick for the columns a command writes


class Command(Protocol):
    ids: np.ndarray  # the entities it names (none for a one-shot system's run, one_shot.py)

    def apply(self, storage: Storage, tick: Tick) -> None: ...


@dataclass(slots=True)
class Spawn:
    ids: np.ndarray
    types: frozenset[type[Component]]
    checked: Checked

    def apply(self, storage: Storage, tick: Tick) -> None:
        storage.place(self.ids, self.types, self.checked, tick())


@dataclass(slots=True)
class Destroy:
    ids: np.ndarray

    def apply(self, storage: Storage, tick: Tick) -> None:
        here = present(storage, self.ids)
        if here is None or here.any():
            storage.destroy(self.ids if here is None else self.ids[here])


@dataclass(slots=True)
class Add:
    ids: np.ndarray
    component: type[Component]
    values: Values

    def apply(self, storage: Storage, tick: Tick) -> None:
        here = present(storage, self.ids)
        if here is None:
            storage.add(self.ids, self.component, self.values, tick())
        elif here.any():
            storage.add(self.ids[here], self.component, select_rows(self.values, here, len(self.ids)), tick())


@dataclass(slots=True)
class Remove:
    """A queued remove of a component the entity no longer has is skipped."""

    ids: np.ndarray
    component: type[Component]

    def apply(self, storage: Storage, tick: Tick) -> None:
        here = present(storage, self.ids)
        if here is None or here.any():
            storage.remove(self.ids if here is None else self.ids[here], self.component, False, tick())


@dataclass(slots=True)
class Set:
    """A partial set is checked against the other fields' values when it is applied: they may
    have been spawned or added by earlier commands of the same queue."""

    ids: np.ndarray
    component: type[Component]
    values: Values
    who: Callable[[int], str]

    def apply(self, storage: Storage, tick: Tick) -> None:
        ct, ids, values, who = self.component, self.ids, self.values, self.who
        here = present(storage, ids)
        if here is not None:
            if not here.any():
                return
            ids, values = ids[here], select_rows(values, here, len(ids))
            who = lambda row: describe_entity(int(ids[row]))  # rows of the entities left
        if len(values) < len(ct.__fields__) and storage.all_have(ids, ct):
            ct.check({**storage.stored(ids, ct), **values}, who)
        storage.write(ids, ct, values, tick())


def present(storage: Storage, ids: np.ndarray) -> np.ndarray | None:
    """None when every id names an entity in a table; else the mask of those that do, the others
    destroyed by an earlier command of this sync point. An id whose spawn comes in a later
    command raises (a system declared before the spawning one used it)."""
    index = storage.index
    valid = index.valid(ids)
    placed = valid & (index.table[np.where(valid, ids & INDEX_MASK, 0)] >= 0)
    if placed.all():
        return None
    waiting = valid & ~placed
    if waiting.any():
        bad = int(ids[waiting][0])
        raise DeadEntityError(
            f"{describe_entity(bad)} is spawned by a later command of this sync point (a system declared "
            "after the one that used it)"
        )
    return placed


class CommandQueue:
    """Commands in request order, and the ids queued for destruction (using one raises)."""

    def __init__(self) -> None:
        self.commands: list[Command] = []  # read it to skip an empty queue without a call
        self.pending_destroy: set[int] = set()
        self._touched: set[int] = set()  # every id a queued command names

    def __len__(self) -> int:
        return len(self.commands)

    def push(self, command: Command) -> None:
        if isinstance(command, Destroy):
            self.pending_destroy.update(command.ids.tolist())
        self._touched.update(command.ids.tolist())
        self.commands.append(command)

    def extend(self, other: CommandQueue) -> None:
        """Append `other`'s commands (a parallel system's queue) in their order; empties it."""
        for command in other.commands:
            self.push(command)
        other.commands = []
        other.pending_destroy.clear()
        other._touched.clear()

    def touches(self, ids: np.ndarray) -> bool:
        """Whether a queued command names one of `ids` (so a later write must queue behind it)."""
        return bool(self._touched) and not self._touched.isdisjoint(ids.tolist())

    def apply(self, storage: Storage, tick: Tick) -> None:
        """Apply every command; one that fails changes nothing and is reported (the first, with a
        count of the others) after all the others were applied."""
        if not self.commands:
            return  # nothing queued (most sync points): push fills the two sets only with a command
        commands, self.commands = self.commands, []
        self.pending_destroy.clear()
        self._touched.clear()
        errors: list[Exception] = []
        for command in commands:
            try:
                command.apply(storage, tick)
            except (EcsError, ValueError) as exc:  # a missing entity or component, a failed check
                errors.append(exc)
        if errors:
            more = f" (and {len(errors) - 1} more failed commands)" if len(errors) > 1 else ""
            raise type(errors[0])(f"{errors[0]}{more}")
