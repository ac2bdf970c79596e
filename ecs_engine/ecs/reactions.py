"""What runs at a sync point once its structural changes are applied: the removal channels are
filled (removals.py), the observers run (observers.py), then the one-shot systems requested
there (one_shot.py); what those change is applied and may set off more, in rounds, until
nothing is left or `MAX_ROUNDS` says they loop.

A world makes this on first use (`World.add_observer`, `removed`, `run_once`): one that uses
none of them pays one attribute test per sync point and per structural change.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

from .entities import INDEX_MASK
from .errors import EcsError
from .lifecycle import LifecycleLog
from .observers import MAX_ROUNDS, Observer, Trigger, structural_trigger
from .removals import Removals
from .running import RunningSystem
from .schema import Component, schema_of
from .storage import Storage


class Reactions:
    def __init__(self) -> None:
        self.observers: list[Observer] = []
        self.removal_channels: dict[type[Component], Removals] = {}
        self.pending: list[tuple[RunningSystem, float]] = []  # one-shot systems requested (RunSystem commands)
        self.one_shots: dict[Any, RunningSystem] = {}  # function -> its system, made once (one_shot.py)
        self._lock = threading.Lock()  # systems of a parallel stage may ask for a channel at once

    # ------------------------------------------------------------------ registering
    def add_observer(self, storage: Storage, observer: Observer) -> None:
        if any(o is observer for o in self.observers):
            raise ValueError(f"{observer!r} is already added")
        self.observers.append(observer)
        self._watch(storage)

    def remove_observer(self, storage: Storage, observer: Observer) -> None:
        if not any(o is observer for o in self.observers):
            raise ValueError(f"{observer!r} is not an observer of this world")
        self.observers = [o for o in self.observers if o is not observer]
        self._watch(storage)

    def removals(self, world: Any, component: type) -> Removals:
        ct = schema_of(component)
        channel = self.removal_channels.get(ct)
        if channel is None:
            with self._lock:
                channel = self.removal_channels.get(ct)
                if channel is None:
                    channel = Removals(ct, world)
                    world._events[(Removals, ct)] = channel  # turned over with the event channels
                    self.removal_channels[ct] = channel
                    self._watch(world.storage)
        return channel

    def _watch(self, storage: Storage) -> None:
        """What the storage records: exactly what some observer or removal channel wants."""
        added = {o.trigger.component for o in self.observers if o.trigger.kind == "add"}
        kept = {o.trigger.component for o in self.observers if o.trigger.kind == "remove"}
        removed = kept | set(self.removal_channels)
        if not added and not removed:
            storage.log = None
            return
        log = storage.log if storage.log is not None else LifecycleLog()
        log.added, log.removed, log.kept = frozenset(added), frozenset(removed), frozenset(kept)
        storage.log = log

    # --------------------------------------------------------------------- running
    def run(self, world: Any) -> None:
        """The sync point's reactions, in rounds (see the module): the observers, their changes
        applied, then each one-shot system requested and its changes. An error is raised as it
        was once the round's other work ran and the changes it asked for were applied."""
        storage: Storage = world.storage
        for _ in range(MAX_ROUNDS):
            changes = storage.log.take() if storage.log is not None else []
            for change in changes:  # first: an observer may read them
                channel = self.removal_channels.get(change.component) if change.kind == "remove" else None
                if channel is not None:
                    channel.record(change.entities)
            ran: list[str] = []
            errors: list[Exception] = []
            for observer in self.observers:
                if observer.trigger.kind == "change":
                    trigger = changed_trigger(world, observer)
                elif changes:
                    trigger = structural_trigger(observer, changes, lambda ids, ct: holding(storage, ids, ct))
                else:
                    continue
                if trigger is not None:
                    observer.pending = trigger
                    _run(world, observer, 0.0, errors)
                    ran.append(observer.name)
            _apply(world, errors)  # what the observers asked for
            pending, self.pending = self.pending, []
            for system, dt in pending:
                _run(world, system, dt, errors)
                _apply(world, errors)  # what it asked for, before the next one runs
                ran.append(system.name)
            if errors:
                raise errors[0]
            if not ran:
                return
        raise EcsError(
            f"observers and one-shot systems kept changing the world for {MAX_ROUNDS} rounds at one sync point "
            f"(the last round ran {', '.join(sorted(set(ran)))}): one reacts to its own changes"
        )


def _run(world: Any, system: RunningSystem, dt: float, errors: list[Exception]) -> None:
    try:
        world.run_system(system, dt)
    except Exception as exc:  # raised after the round (Reactions.run)
        errors.append(exc)


def _apply(world: Any, errors: list[Exception]) -> None:
    """The structural changes queued meanwhile (a failed one raised after the round)."""
    if len(world._queue):
        try:
            world._queue.apply(world.storage, world.write_tick)
        except (EcsError, ValueError) as exc:
            errors.append(exc)


def changed_trigger(world: Any, observer: Observer) -> Trigger | None:
    """Every entity of the tables where a column of the observer's component was written since
    it last ran (ticks are per table column: see observers.py)."""
    ct = observer.trigger.component
    since = observer.last_run_tick
    keys = [(ct, name) for name in ct.__fields__]
    found = []
    for table in world.query(ct, write=()).tables:
        if table.count and any(table.column_ticks[k] > since for k in keys):
            found.append(table.entities[: table.count])
    if not found:
        return None
    ids = np.concatenate(found)
    ids.flags.writeable = False
    return Trigger("change", ct, ids)


def holding(storage: Storage, ids: np.ndarray, ct: type[Component]) -> np.ndarray:
    """Which of `ids` name live entities that have `ct` (vectorised)."""
    index = storage.index
    ok = index.valid(ids)
    table = index.table[np.where(ok, ids & INDEX_MASK, 0)]
    ok &= table >= 0
    has = np.fromiter((ct in t.type_set for t in storage.tables), bool, len(storage.tables))
    return ok & has[np.where(ok, table, 0)]
