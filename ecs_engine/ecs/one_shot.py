"""One-shot systems (Bevy's `run_system`): a system run on request instead of every frame.

    @system(reads=[Wave], writes=[Enemy])
    def spawn_wave(world, dt): ...

    run_once(world, spawn_wave)   # outside systems: runs now, then its sync point

    @system(reads=[Score])
    def check(world, dt):
        if ...: run_once(world, spawn_wave)   # inside a system: at this stage's sync point

Requested inside a system (or a query loop, or a `world.deferred()` block), it runs at the sync
point that applies the requester's structural changes, after them and after that sync point's
observers, in request order (a parallel stage joins its systems' requests in declared order),
each one's changes applied before the next runs; requested outside them, it runs at once and its
changes are applied when it returns. It runs as
a system: its own change tick and event cursors (kept between runs: a function is made into one
system per world, the first time), and its declared `reads`/`writes` are checked as a scheduled
system's are.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .running import RunningSystem
from .schedule import FunctionSystem, System
from .storage import Storage
from .world import World


class RunSystem:
    """The queued request: at the sync point it hands the system to the reactions (reactions.py),
    which run it once the structural changes queued with it are applied."""

    __slots__ = ("dt", "pending", "system")
    ids = np.empty(0, np.int64)  # names no entity (CommandQueue keeps the ids commands name)

    def __init__(self, pending: list[tuple[RunningSystem, float]], system: RunningSystem, dt: float) -> None:
        self.pending, self.system, self.dt = pending, system, dt

    def apply(self, storage: Storage, tick: Callable[[], int]) -> None:
        self.pending.append((self.system, self.dt))


def run_once(world: World, system: System | Callable[[World, float], Any], dt: float = 0.0) -> None:
    """Run `system` once: now outside systems, at the next sync point inside one (see the module)."""
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating, np.integer)) or not math.isfinite(dt):
        raise ValueError(f"run_once: dt is a finite number of seconds, got {dt!r}")
    reactions = world._reacting()
    if isinstance(system, System):
        one = system
    elif callable(system):
        found = reactions.one_shots.get(system)
        one = found if isinstance(found, System) else FunctionSystem(system, reads=None, writes=None)
        reactions.one_shots[system] = one
    else:
        raise TypeError(f"run_once takes a system or a function of (world, dt), got {type(system).__name__} {system!r}")
    if world.deferring:
        world._commands.push(RunSystem(reactions.pending, one, float(dt)))
        return
    world.run_system(one, float(dt))
    world.flush()
