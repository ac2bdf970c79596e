"""Removal detection (Bevy's RemovedComponents): which entities lost a component, or were
destroyed with it, as an array of ids per reader.

    @system(reads=[Health])
    def forget(world, dt):
        gone = world.removed(Health).read()  # int64 ids, each removal seen once by this system

A removal channel is an event channel (events.py) whose events are the ids: double-buffered per
frame, each reader (the running system, or a `Reader` kept outside systems) sees each removal
once if it reads at least every other frame; one that falls further behind loses the oldest
(`dropped`). Removals are recorded from the first `world.removed(C)` on (call it while setting
up to have them from the start), at the sync point where they are applied. A system that reads
them declares the component in `reads`, as for a query.
"""

from __future__ import annotations

import numpy as np

from .events import EventHost, Events, Reader
from .schema import Component, Field, schema_of


class RemovedEntity(Component):
    """One removal: the entity that lost the component (the channel says which component)."""

    entity = Field(np.int64, default=-1)


class Removals(Events[RemovedEntity]):
    """The removal channel of one component (`World.removed(C)` makes and keeps it)."""

    def __init__(self, component: type, host: EventHost | None = None) -> None:
        super().__init__(RemovedEntity, host)
        self.component = schema_of(component)
        self.access = self.component  # a reader declares the component, not the event type
        self.what = f"{self.component.__name__} removals"

    def record(self, ids: np.ndarray) -> None:
        """Entities that lost the component at this sync point (reactions.py)."""
        self.send(RemovedEntity(entity=ids))

    def read(self, reader: Reader | None = None) -> np.ndarray:
        """The ids that lost the component since this reader last read (see the module)."""
        return super().read(reader).entity

    def __repr__(self) -> str:
        return f"<removals of {self.component.__name__}: {len(self)} kept>"
