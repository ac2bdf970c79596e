"""Structural changes requested while systems or query loops run: a typed command queue (as in
Bevy), applied in request order at the next sync point.

Each command holds values the world has already checked and applies itself to the storage, so
the queue needs no dispatch on a kind string and a new command is one small class.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .errors import EcsError
from .schema import Component
from .storage import Checked, Storage, Values

Tick = Callable[[], int]  # the change tick for the columns a command writes


class Command(Protocol):
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
        storage.destroy(self.ids)


@dataclass(slots=True)
class Add:
    ids: np.ndarray
    component: type[Component]
    values: Values

    def apply(self, storage: Storage, tick: Tick) -> None:
        storage.add(self.ids, self.component, self.values, tick())


@dataclass(slots=True)
class Remove:
    """A queued remove of a component the entity no longer has is skipped."""

    ids: np.ndarray
    component: type[Component]

    def apply(self, storage: Storage, tick: Tick) -> None:
        storage.remove(self.ids, self.component, False, tick())


@dataclass(slots=True)
class Set:
    """A partial set is checked against the other fields' values when it is applied: they may
    have been spawned or added by earlier commands of the same queue."""

    ids: np.ndarray
    component: type[Component]
    values: Values
    who: Callable[[int], str]

    def apply(self, storage: Storage, tick: Tick) -> None:
        ct = self.component
        if len(self.values) < len(ct.__fields__) and storage.all_have(self.ids, ct):
            ct.check({**storage.stored(self.ids, ct), **self.values}, self.who)
        storage.write(self.ids, ct, self.values, tick())


class CommandQueue:
    """Commands in request order, and the ids queued for destruction (using one raises)."""

    def __init__(self) -> None:
        self._commands: list[Command] = []
        self.pending_destroy: set[int] = set()
        self._touched: set[int] = set()  # every id a queued command names

    def __len__(self) -> int:
        return len(self._commands)

    def push(self, command: Spawn | Destroy | Add | Remove | Set) -> None:
        if isinstance(command, Destroy):
            self.pending_destroy.update(command.ids.tolist())
        self._touched.update(command.ids.tolist())
        self._commands.append(command)

    def extend(self, other: CommandQueue) -> None:
        """Append `other`'s commands (a parallel system's queue) in their order; empties it."""
        for command in other._commands:
            self.push(command)  # type: ignore[arg-type]
        other._commands = []
        other.pending_destroy.clear()
        other._touched.clear()

    def touches(self, ids: np.ndarray) -> bool:
        """Whether a queued command names one of `ids` (so a later write must queue behind it)."""
        return bool(self._touched) and not self._touched.isdisjoint(ids.tolist())

    def apply(self, storage: Storage, tick: Tick) -> None:
        """Apply every command; one that fails changes nothing and is reported (the first, with a
        count of the others) after all the others were applied."""
        if not self._commands:
            return  # nothing queued (most sync points): push fills the two sets only with a command
        commands, self._commands = self._commands, []
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
