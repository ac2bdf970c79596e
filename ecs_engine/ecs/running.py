"""Running systems in a world: what each thread runs (the parallel schedule runs several
systems at once), one system's run and a group's run together."""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from .commands import CommandQueue
from .read_only_writes import is_read_only_write, read_only_write_error


class RunningSystem(Protocol):
    """What the world needs of a system while it runs it (see schedule.System)."""

    name: str
    reads: frozenset[type] | None
    writes: frozenset[type] | None
    last_run_tick: int

    def run(self, world: Any, dt: float) -> None: ...


class Running:
    """What runs: the system (the parallel schedule runs several at once), its change tick, the
    query loops open, and the command queue of a system run in parallel (merged into the world's
    in the schedule's declared order after the group). A plain object while one thread runs the
    world; `ThreadRunning` (one per thread) while a parallel group runs: reading a thread-local
    costs every query and write, so only that case pays it (1-cube frame: 43 -> 30 us here)."""

    system: Any = None  # the world's RunningSystem
    tick: int = 0
    iter_depth: int = 0
    commands: CommandQueue | None = None
    lane: int | None = None  # the system's place in the schedule stage running (for its ids)


class ThreadRunning(Running, threading.local):
    """Running, one per thread: the world uses it while systems run together."""


def run_as(
    world: Any,
    local: Running,
    system: RunningSystem,
    dt: float,
    tick: int,
    queue: CommandQueue | None,
    lane: int | None,
) -> None:
    """Run `system` in `world` as what `local` (this thread's) says runs."""
    local.system, local.tick, local.commands, local.lane = system, tick, queue, lane
    try:
        system.run(world, dt)
    except ValueError as exc:  # free while nothing is raised (Python 3.11+): systems that behave pay nothing
        if not is_read_only_write(exc):
            raise
        error = read_only_write_error(exc, system, world.storage.tables)
        raise error.with_traceback(exc.__traceback__) from None
    finally:
        local.system, local.commands, local.lane = None, None, None
        system.last_run_tick = tick


def run_group(
    world: Any,
    local: Running,
    systems: Sequence[RunningSystem],
    dt: float,
    spread: Callable[[Callable[[int], None], range], Any],
    queues: Sequence[CommandQueue],
    lanes: Sequence[int],
    ticks: Sequence[int],
) -> None:
    """World.run_systems_together's jobs; a system's error is raised as it was, after all ran."""
    errors: list[BaseException | None] = [None] * len(systems)

    def job(i: int) -> None:
        try:
            run_as(world, local, systems[i], dt, ticks[i], queues[i], lanes[i])
        except BaseException as exc:  # re-raised below, as the system raised it
            errors[i] = exc

    spread(job, range(len(systems)))
    for exc in errors:
        if exc is not None:
            raise exc
