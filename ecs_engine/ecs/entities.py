"""Entity ids: 64 bits, generation in the high half and slot index in the low half.

A slot's generation is bumped when its entity is destroyed, so an old id never matches again.
A slot whose generation would overflow is retired, never reused: a destroyed id can never name a
new entity. Generations start at 1, so 0 is never a valid id and can serve as "no entity".
"""

from __future__ import annotations

import numpy as np

INDEX_BITS = 32
INDEX_MASK = (1 << INDEX_BITS) - 1
MAX_GENERATION = (1 << 31) - 1

# location_table values other than a table id
FREE = -1
RESERVED = -2  # id handed out by a deferred spawn, not yet placed in a table


def make_ids(index: np.ndarray, generation: np.ndarray) -> np.ndarray:
    return (generation.astype(np.int64) << INDEX_BITS) | index.astype(np.int64)


class EntityIndex:
    """Slot arrays (generation, table, row) grown by doubling, plus a free list."""

    def __init__(self, capacity: int = 1024) -> None:
        self.generation = np.ones(capacity, dtype=np.int64)
        self.table = np.full(capacity, FREE, dtype=np.int32)
        self.row = np.zeros(capacity, dtype=np.int64)
        self.used = 0  # slots ever handed out
        self._free = np.empty(0, dtype=np.int64)
        self._free_count = 0

    # ----------------------------------------------------------------- capacity
    def _ensure(self, needed: int) -> None:
        cap = len(self.generation)
        if needed <= cap:
            return
        new_cap = max(needed, 2 * cap)
        self.generation = _grown(self.generation, new_cap, 1)
        self.table = _grown(self.table, new_cap, FREE)
        self.row = _grown(self.row, new_cap, 0)

    def nbytes(self) -> int:
        return self.generation.nbytes + self.table.nbytes + self.row.nbytes + self._free.nbytes

    # --------------------------------------------------------------- allocation
    def allocate(self, n: int) -> np.ndarray:
        """Return n fresh ids (slots reused from the free list first). Location is left FREE."""
        take = min(n, self._free_count)
        reused = self._free[self._free_count - take : self._free_count][::-1].copy()
        self._free_count -= take
        fresh_n = n - take
        self._ensure(self.used + fresh_n)
        fresh = np.arange(self.used, self.used + fresh_n, dtype=np.int64)
        self.used += fresh_n
        index = np.concatenate([reused, fresh]) if take else fresh
        return make_ids(index, self.generation[index])

    def allocate_one(self) -> int:
        if self._free_count:
            self._free_count -= 1
            index = int(self._free[self._free_count])
        else:
            self._ensure(self.used + 1)
            index = self.used
            self.used += 1
        return (int(self.generation[index]) << INDEX_BITS) | index

    def free_in_pop_order(self) -> np.ndarray:
        """The free slots, the one `allocate` would take next first."""
        return self._free[: self._free_count][::-1].copy()

    def replace_free(self, pop_order: np.ndarray) -> None:
        """Make these slots the free list, the first one to be taken next."""
        self._free = np.array(pop_order[::-1], dtype=np.int64)
        self._free_count = len(self._free)

    def claim(self, top: int) -> None:
        """Slots below `top` have been handed out (or skipped, see stage_ids.py): hold them."""
        if top > self.used:
            self._ensure(top)
            self.used = top

    def reserve(self, ids: np.ndarray) -> None:
        """Mark freshly allocated ids as waiting for a deferred spawn (alive, in no table yet)."""
        self.table[ids & INDEX_MASK] = RESERVED

    def release_one(self, index: int) -> None:
        self.table[index] = FREE
        gen = int(self.generation[index]) + 1
        self.generation[index] = gen
        if gen <= MAX_GENERATION:
            if self._free_count == len(self._free):
                self._free = _grown(self._free, max(2 * len(self._free), 64), 0)
            self._free[self._free_count] = index
            self._free_count += 1

    def shrink_to_fit(self) -> None:
        """Drop capacity above the slots ever used (and spare free-list room)."""
        used = max(self.used, 1)
        self.generation = self.generation[:used].copy()
        self.table = self.table[:used].copy()
        self.row = self.row[:used].copy()
        self._free = self._free[: self._free_count].copy()

    def release(self, index: np.ndarray) -> None:
        """Free slots (already removed from their tables): bump generations, recycle or retire."""
        self.table[index] = FREE
        gen = self.generation[index] + 1
        self.generation[index] = gen
        recyclable = index[gen <= MAX_GENERATION]
        need = self._free_count + len(recyclable)
        if need > len(self._free):
            self._free = _grown(self._free, max(need, 2 * len(self._free), 64), 0)
        self._free[self._free_count : need] = recyclable
        self._free_count = need

    # ------------------------------------------------------------------- lookup
    def split(self, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ids = np.asarray(ids, dtype=np.int64)
        return ids & INDEX_MASK, ids >> INDEX_BITS

    def valid(self, ids: np.ndarray) -> np.ndarray:
        """Mask of ids that name a live (or reserved) entity."""
        index, gen = self.split(ids)
        ok = (ids > 0) & (index < self.used)
        safe = np.where(ok, index, 0)
        return ok & (self.generation[safe] == gen) & (self.table[safe] != FREE)

    def valid_one(self, eid: int) -> bool:
        index = eid & INDEX_MASK
        return (
            eid > 0
            and index < self.used
            and int(self.generation[index]) == eid >> INDEX_BITS
            and int(self.table[index]) != FREE
        )


def _grown(arr: np.ndarray, new_cap: int, fill: int) -> np.ndarray:
    out = np.full(new_cap, fill, dtype=arr.dtype)
    out[: len(arr)] = arr
    return out
