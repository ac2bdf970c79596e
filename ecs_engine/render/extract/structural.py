"""Answers about a world that only a spawn, destroy, add or remove can change (whether some
entity has a component at all), asked every frame by the extract stage: each is kept per world
until its structure version moves, so a frame pays a dictionary lookup, not a query."""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import Any

# per world: name -> (structure version, answer)
_KEPT: weakref.WeakKeyDictionary[Any, dict[str, tuple[int, Any]]] = weakref.WeakKeyDictionary()


def structural(world: Any, name: str, answer: Callable[[Any], Any]) -> Any:
    """`answer(world)`, kept under `name` until the world's structure changes."""
    version = world.structure_version
    kept = _KEPT.get(world)
    if kept is None:
        kept = _KEPT[world] = {}
    last = kept.get(name)
    if last is not None and last[0] == version:
        return last[1]
    value = answer(world)
    kept[name] = (version, value)
    return value
