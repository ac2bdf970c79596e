"""Answers about a world that only a spawn, destroy, add or remove can change (whether some
entity has a component at all, which camera is the active one), asked every frame: each is kept
on the world's storage until its structure version moves, so a frame pays a lookup, not a query.
Kept on the storage rather than in a table of worlds: no weak references to follow, and a world
asked in turn with another keeps its own answers."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

_MISSING = object()


def structural(world: Any, name: str, answer: Callable[[Any], Any]) -> Any:
    """`answer(world)`, kept under `name` until the world's structure changes (one name, one
    question: two answers under a name would be taken for each other; schedule.py's AnyWith
    keeps its answers here under itself)."""
    kept = world.storage.answers  # emptied by every structural change (storage.py)
    value = kept.get(name, _MISSING)
    if value is _MISSING:
        value = kept[name] = answer(world)
    return value
