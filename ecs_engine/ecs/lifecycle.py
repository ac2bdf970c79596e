"""What the storage records of entities gaining and losing components, for the observers and
removal readers that asked (reactions.py hands it to them at the sync point).

Nothing is recorded for a component nobody watches: a world without observers or removal
readers has no log at all (`Storage.log` is None), and the structural operations pay one
attribute test. A removal keeps a copy of the component's values as they were, when an
observer wants them (the entity or the component is gone by the time observers run).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .schema import Component
from .table import ArchetypeTable

Kind = Literal["add", "remove"]


@dataclass(slots=True)
class Change:
    kind: Kind
    component: type[Component]
    entities: np.ndarray  # int64 ids
    values: dict[str, np.ndarray] | None  # a removal's field values, one row per entity (when kept)


class LifecycleLog:
    """Changes to the watched components, in the order they were applied."""

    def __init__(self) -> None:
        self.added: frozenset[type[Component]] = frozenset()  # components whose additions are recorded
        self.removed: frozenset[type[Component]] = frozenset()  # ... whose removals are recorded
        self.kept: frozenset[type[Component]] = frozenset()  # ... whose removed values are kept
        self.changes: list[Change] = []

    def watch(self, kind: Kind, component: type[Component], keep_values: bool = False) -> None:
        if kind == "add":
            self.added |= {component}
        else:
            self.removed |= {component}
            if keep_values:
                self.kept |= {component}

    def take(self) -> list[Change]:
        changes, self.changes = self.changes, []
        return changes

    # ------------------------------------------------------------ recording (storage.py)
    def placed(self, types: frozenset[type[Component]], ids: np.ndarray) -> None:
        """New entities with `types` (a spawn)."""
        for ct in self.added:
            if ct in types:
                self.changes.append(Change("add", ct, ids.copy(), None))

    def moved(self, src: ArchetypeTable, dst: ArchetypeTable, rows: np.ndarray, ids: np.ndarray) -> None:
        """Entities about to move between tables (an add or a remove): what they gain and lose."""
        for ct in self.removed:
            if ct in src.type_set and ct not in dst.type_set:
                self._removal(ct, src, rows, ids)
        for ct in self.added:
            if ct in dst.type_set and ct not in src.type_set:
                self.changes.append(Change("add", ct, np.array(ids, np.int64), None))

    def destroyed(self, table: ArchetypeTable, rows: np.ndarray, ids: np.ndarray) -> None:
        """Entities about to be destroyed: they lose every component of their table."""
        for ct in self.removed:
            if ct in table.type_set:
                self._removal(ct, table, rows, ids)

    def _removal(self, ct: type[Component], table: ArchetypeTable, rows: np.ndarray, ids: np.ndarray) -> None:
        values = None
        if ct in self.kept:
            values = {name: table.columns[(ct, name)][rows] for name in ct.__fields__}  # fancy index: a copy
        self.changes.append(Change("remove", ct, np.array(ids, np.int64), values))
