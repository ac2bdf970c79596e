"""Typed event channels, double-buffered per frame (as Bevy's Events): one system sends, others
read, and each reader sees each event once.

    @system(writes=[Hit])            # sending declares the event type as written
    def shoot(world, dt): world.events(Hit).send(Hit(target=e, damage=3.0))

    @system(reads=[Hit], writes=[Health])
    def damage(world, dt):
        for hit in world.events(Hit).read(): ...

- A channel keeps the events sent this frame and the last one; `Schedule` calls
  `World.update_events()` after each frame, which drops the older frame. So a reader that runs
  every frame, before or after the sender, sees every event exactly once; one that skips two
  frames loses what was sent meanwhile (`dropped` counts it).
- Each reader has a cursor: the running system by default, or a `Reader` you keep (outside
  systems). Readers never consume events for one another.
- Events of a `Component` type are columns: `send(Hit(target=ids, damage=d))` sends one event
  per row (fields shared or per row, checked like a spawn), and `read()` returns a `Columns` whose
  fields are the concatenated arrays, for vectorised handling of thousands of events. Events of
  any other class are objects, read back as a list.
- The event type is the access the schedule sees: a system that sends declares it in `writes`,
  one that reads in `reads` (or `writes`); so senders never run alongside readers or each other
  (schedule.py). Undeclared systems (reads/writes None) may do anything.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Generic, Protocol, TypeVar

import numpy as np

from .errors import AccessError
from .schema import Component, schema_of

T = TypeVar("T")


class EventHost(Protocol):
    """What a channel needs of its world: the system running on this thread (or None)."""

    def running_system(self) -> Any: ...


@dataclass(eq=False)
class Reader:
    """A read position in a channel, for reading outside systems (systems get one each)."""

    position: int = 0


class Columns:
    """Column events read at once: `columns.damage` is one array, a row per event."""

    def __init__(self, kind: type[Component], arrays: dict[str, np.ndarray], count: int) -> None:
        self.kind = kind
        self.count = count
        self.__dict__.update(arrays)

    def __len__(self) -> int:
        return self.count

    def __getattr__(self, name: str) -> Any:
        raise AttributeError(f"{self.kind.__name__} events have no field {name!r}")


@dataclass(eq=False)
class _Frame:
    start: int  # the sequence number of its first event
    items: list[Any] = field(default_factory=list)  # objects, or (dict of column arrays, rows)
    count: int = 0  # events (rows, for column events)


class Events(Generic[T]):
    """The channel of one event type (`World.events(kind)` makes and keeps it)."""

    def __init__(self, kind: type[T], host: EventHost | None = None) -> None:
        if not isinstance(kind, type):
            raise TypeError(f"an event type is a class, got {kind!r}")
        self.kind = kind
        self.access = schema_of(kind)  # how systems declare it
        self.what = f"{kind.__name__} events"  # in errors
        self.host = host
        self.columns = issubclass(kind, Component)
        self._previous = _Frame(0)
        self._current = _Frame(0)
        self._cursors: dict[int, Reader] = {}  # id(system) -> its reader
        self._owners: dict[int, Any] = {}  # keeps each system alive while its id is a key
        self.dropped = 0  # events a reader missed because it fell two frames behind

    def _system(self, writing: bool) -> Any:
        """The running system, after checking that it declared this event type."""
        system = self.host.running_system() if self.host is not None else None
        if system is None or system.writes is None:
            return system
        allowed = system.writes if writing else (system.writes | (system.reads or frozenset()))
        if self.access not in allowed:
            verb, where = ("sends", "writes") if writing else ("reads", "reads")
            raise AccessError(f"system {system.name} {verb} {self.what} but does not declare them in {where}")
        return system

    # ---------------------------------------------------------------- sending
    def send(self, event: T) -> None:
        """Send one event; for a Component type, one per row of its fields."""
        if not isinstance(event, self.kind):
            name = self.kind.__name__
            raise TypeError(f"a {name} channel takes {name} events, got {type(event).__name__}")
        self._system(writing=True)
        if not self.columns:
            self._current.items.append(event)
            self._current.count += 1
            return
        arrays, n = self._rows(event)
        self._current.items.append((arrays, n))
        self._current.count += n

    def send_rows(self, arrays: dict[str, np.ndarray], n: int) -> None:
        """Send n column events made by engine code in bulk: one array per field, of its dtype
        and n rows of its shape, kept as they are (not checked for values, not copied: the
        caller gives them up). Checking and copying cost more than making them when a handful
        of events comes after a physics step that evicted every cache."""
        kind: type[Component] = self.kind  # type: ignore[assignment]
        fields = kind.__fields__
        for name, f in fields.items():
            v = arrays.get(name)
            if v is None or v.dtype != f.dtype or v.shape != (n, *f.shape):
                got = "nothing" if v is None else f"{v.dtype} {v.shape}"
                raise TypeError(f"{kind.__name__}.{name}: send_rows takes {f.dtype} {(n, *f.shape)}, got {got}")
        self._system(writing=True)
        self._current.items.append((arrays, n))
        self._current.count += n

    def send_batch(self, events: list[T]) -> None:
        for event in events:
            self.send(event)

    def _rows(self, event: Any) -> tuple[dict[str, np.ndarray], int]:
        """The event's fields checked and broadcast to one length (the longest given)."""
        kind: type[Component] = self.kind  # type: ignore[assignment]
        fields = kind.__fields__
        raw = {name: np.asarray(getattr(event, name)) for name in fields}
        n = max((len(v) for name, v in raw.items() if v.shape != fields[name].shape and v.ndim), default=1)
        values = {name: f.coerce(raw[name], n) for name, f in fields.items()}
        kind.check(values, lambda row: f"{kind.__name__} event {row}")
        shapes = {name: (n, *f.shape) for name, f in fields.items()}
        # (a column of n rows already is copied as it is: broadcast_to costs more than the copy)
        return {
            name: v.copy() if v.shape == shapes[name] else np.broadcast_to(v, shapes[name]).copy()
            for name, v in values.items()
        }, n

    # ---------------------------------------------------------------- reading
    def read(self, reader: Reader | None = None) -> Any:
        """The events this reader has not seen (sent last frame or this one): a list of objects,
        or a `Columns` for a Component type. Without a reader: the running system's own, or
        outside systems every kept event."""
        system = self._system(writing=False)
        if reader is None:
            if system is None:
                reader = Reader(self._previous.start)
            else:
                reader = self._cursors.get(id(system))
                if reader is None:
                    reader = self._cursors[id(system)] = Reader(self._previous.start)
                    self._owners[id(system)] = system
        oldest = self._previous.start
        if reader.position < oldest:
            self.dropped += oldest - reader.position
            reader.position = oldest
        end = self._current.start + self._current.count
        chosen: list[Any] = []
        for frame in (self._previous, self._current):
            skip = reader.position - frame.start
            for item in frame.items:
                size = item[1] if self.columns else 1
                if skip >= size:
                    skip -= size
                    continue
                if self.columns:
                    chosen.append(({k: v[skip:] for k, v in item[0].items()}, size - skip) if skip else item)
                else:
                    chosen.append(item)
                skip = 0
        reader.position = end
        if not self.columns:
            return chosen
        kind: type[Component] = self.kind  # type: ignore[assignment]
        arrays = {
            name: np.concatenate([c[0][name] for c in chosen]) if chosen else np.empty((0, *f.shape), f.dtype)
            for name, f in kind.__fields__.items()
        }
        return Columns(kind, arrays, sum(c[1] for c in chosen))

    def __len__(self) -> int:
        """Events kept (last frame's and this frame's)."""
        return self._previous.count + self._current.count

    def update(self) -> None:
        """The frame boundary: last frame's events go, this frame's become last frame's."""
        self._previous = self._current
        self._current = _Frame(self._previous.start + self._previous.count)

    def clear(self) -> None:
        """Drop every kept event (readers skip past them)."""
        start = self._current.start + self._current.count
        self._previous, self._current = _Frame(start), _Frame(start)
