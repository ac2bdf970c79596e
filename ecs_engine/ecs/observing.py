"""The world's methods for what reacts to structural changes: observers (observers.py), removal
channels (removals.py) and the reactions' place in a sync point (reactions.py). Kept out of
world.py, which holds the storage's API."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from .observers import Observer, ObserverFunction, ObserverTrigger
from .reactions import Reactions
from .removals import Removals
from .storage import Storage


class Observing:
    """Mixed into World (these are its attributes)."""

    storage: Storage
    tick: int
    _reactions: Reactions | None
    _held: int
    _ids_lock: threading.Lock

    def add_observer(self, trigger: ObserverTrigger, fn: ObserverFunction, **named: Any) -> Observer:
        """Run `fn(world, trigger)` with the entities that gain, lose or change a component, in
        bulk, at each sync point (observers.py); `named`: name, reads, writes."""
        observer = Observer(trigger, fn, **named)
        observer.last_run_tick = self.tick  # OnChange: the changes from now on
        self._reacting().add_observer(self.storage, observer)
        return observer

    def remove_observer(self, observer: Observer) -> None:
        self._reacting().remove_observer(self.storage, observer)

    def removed(self, component_type: type) -> Removals:
        """The removal channel of a component: `.read()` gives the ids that lost it (removals.py)."""
        return self._reacting().removals(self, component_type)

    def _reacting(self) -> Reactions:
        if self._reactions is None:
            with self._ids_lock:
                self._reactions = self._reactions or Reactions()
        return self._reactions

    def _react(self) -> None:
        """A sync point, or a structural change applied at once: its reactions run."""
        if not self._held and self._reactions is not None:
            self._reactions.run(self)

    @contextmanager
    def observers_held(self) -> Iterator[Any]:
        """Observers wait for the end of the block and see its changes as one batch (a scene
        load, a prefab spawn); a block that raises (and undoes its changes) reports none."""
        log = self.storage.log
        mark = len(log.changes) if log is not None else 0
        self._held += 1
        try:
            yield self
        except BaseException:
            if log is not None and log is self.storage.log:
                del log.changes[mark:]
            raise
        finally:
            self._held -= 1
        self._react()
