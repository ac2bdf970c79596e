"""Entity ids for the spawns of one schedule stage: the same ids whatever order its systems run
in, one after another or at the same time on several threads.

While a stage runs, structural changes wait for its sync point, so nothing changes the entity
index there but the ids that spawns take. Those come from the stage's sequence of slots: the
free list in the order `EntityIndex.allocate` pops it, then fresh slots. System k of a stage of
n takes its c-th block of BLOCK slots at position (c * n + k) * BLOCK of that sequence, so which
ids it gets depends only on the index at the stage's start, its place in the stage and its own
spawns: never on the other systems or on which thread came first. A stage of one system takes
the sequence in order, as `allocate` would. At the sync point the slots no system took go back
to the free list (a stage's systems leave gaps among the fresh slots only up to n blocks).
"""

from __future__ import annotations

import numpy as np

from .entities import INDEX_BITS, EntityIndex, make_ids

BLOCK = 64


class StageIds:
    """Hands out the ids of one stage; the caller holds the world's id lock (see the module)."""

    def __init__(self, index: EntityIndex, systems: int) -> None:
        self.index = index
        self.lanes = max(systems, 1)
        self._next = [0] * self.lanes  # per system: the next position of its block, and its end
        self._end = [0] * self.lanes
        self._blocks = [0] * self.lanes  # blocks taken so far
        self._free = index.free_in_pop_order()  # at the stage's start: nothing else takes ids
        self._used = index.used
        self._released = len(self._free)  # slots released meanwhile (not by systems) are kept
        self._taken: list[np.ndarray] = []  # positions handed out
        self._taken_one: list[int] = []  # by single spawns

    def take(self, lane: int, n: int) -> np.ndarray:
        """n new ids for the system at place `lane` of the stage."""
        nxt = self._next[lane]
        if n == 1 and nxt < self._end[lane]:  # one spawn at a time: Python ints, no arrays
            self._next[lane] = nxt + 1
            self._taken_one.append(nxt)
            free = len(self._free)
            slot = int(self._free[nxt]) if nxt < free else self._used + nxt - free
            self.index.claim(slot + 1)
            return np.array([(int(self.index.generation[slot]) << INDEX_BITS) | slot], dtype=np.int64)
        positions = self._positions(lane, n)
        self._taken.append(positions)
        slots = np.empty(n, dtype=np.int64)
        free = len(self._free)
        old = positions < free
        slots[old] = self._free[positions[old]]
        slots[~old] = self._used + positions[~old] - free
        if n:
            self.index.claim(int(slots.max()) + 1)
        return make_ids(slots, self.index.generation[slots])

    def _positions(self, lane: int, n: int) -> np.ndarray:
        nxt, end = self._next[lane], self._end[lane]
        first = min(n, end - nxt)
        parts = [np.arange(nxt, nxt + first, dtype=np.int64)]
        nxt += first
        rest = n - first
        if rest:
            count = -(-rest // BLOCK)
            starts = (
                np.arange(self._blocks[lane], self._blocks[lane] + count, dtype=np.int64) * self.lanes + lane
            ) * BLOCK
            parts.append((starts[:, None] + np.arange(BLOCK)).ravel()[:rest])
            self._blocks[lane] += count
            end = int(starts[-1]) + BLOCK
            nxt = end - (count * BLOCK - rest)
        self._next[lane], self._end[lane] = nxt, end
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    def close(self) -> None:
        """The stage's sync point: the free list keeps the slots no system took, and gets the
        fresh slots skipped between blocks (lowest first out)."""
        if not self._taken and not self._taken_one:
            return
        taken = np.concatenate([*self._taken, np.array(self._taken_one, dtype=np.int64)])
        free = len(self._free)
        kept = np.ones(free, dtype=bool)
        kept[taken[taken < free]] = False
        skipped = np.ones(self.index.used - self._used, dtype=bool)
        skipped[taken[taken >= free] - free] = False
        gaps = self._used + np.flatnonzero(skipped)
        now = self.index.free_in_pop_order()
        released = now[: len(now) - self._released]
        self.index.replace_free(np.concatenate([released, self._free[kept], gaps]))
