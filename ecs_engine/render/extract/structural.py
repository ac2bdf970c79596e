"""Answers about a world that only a spawn, destroy, add or remove can change (whether some
entity has a component at all), asked every frame by the extract stage: each is kept until the
world's structure version moves, so a frame pays a lookup, not a query."""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import Any

# name -> (the world asked last, its structure version then, the answer); one world per name:
# another world asking is answered anew (a weak reference: a kept answer keeps no world alive)
_LAST: dict[str, tuple[weakref.ref, int, Any]] = {}


def structural(world: Any, name: str, answer: Callable[[Any], Any]) -> Any:
    """`answer(world)`, kept under `name` until the world's structure changes."""
    version = world.structure_version
    last = _LAST.get(name)
    if last is not None and last[1] == version and last[0]() is world:
        return last[2]
    value = answer(world)
    _LAST[name] = (weakref.ref(world), version, value)
    return value
