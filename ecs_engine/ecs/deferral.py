"""The world's methods that decide when structural changes apply: while a query loop, a
`deferred` block or a system runs, spawns, destroys, adds and removes queue (commands.py), and
flush, the sync point, applies them. Systems run here too, one alone or a group together in a
schedule stage whose spawns take ids per system (stage_ids.py), each queueing its changes. Kept
out of world.py, which holds the storage's API, so that each stays a readable size."""

from __future__ import annotations

import threading
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, Self

import numpy as np

from .commands import CommandQueue
from .errors import EcsError
from .reactions import Reactions
from .running import Running, RunningSystem, ThreadRunning, run_as, run_group
from .stage_ids import StageIds
from .storage import Storage


class Deferral:
    """Mixed into World (these are its attributes)."""

    storage: Storage
    tick: int
    _queue: CommandQueue
    _local: Running
    _defer_depth: int
    _ids_lock: threading.Lock
    _stage: tuple[int, StageIds | None] | None
    _reactions: Reactions | None

    if TYPE_CHECKING:  # World's and Observing's methods, which these call

        def write_tick(self) -> int: ...

        def _react(self) -> None: ...

    @property
    def deferring(self) -> bool:
        local = self._local
        return local.iter_depth > 0 or self._defer_depth > 0 or local.system is not None

    @property
    def _commands(self) -> CommandQueue:
        """Where structural changes queue: this thread's parallel system's own queue, else the
        world's."""
        commands = self._local.commands
        return self._queue if commands is None else commands  # not `or`: an empty queue is falsy

    def begin_iteration(self) -> None:
        """A query loop starts: structural changes wait until the last loop ends."""
        self._local.iter_depth += 1

    def end_iteration(self) -> None:
        local = self._local
        local.iter_depth -= 1  # the last loop outside any system and block ended: apply what it queued
        if not local.iter_depth and local.system is None and not self._defer_depth and len(self._queue):
            self.flush()

    # ------------------------------------------------------------ deferral
    @contextmanager
    def deferred(self) -> Iterator[Self]:
        """Queue structural changes made inside the block; apply them when it ends."""
        self._defer_depth += 1
        try:
            yield self
        finally:
            self._defer_depth -= 1
            if not self.deferring and self._commands:
                self.flush()

    def flush(self) -> None:
        """Sync point: apply queued structural changes in the order they were requested.

        A queued `remove` of a component the entity no longer has is skipped; any other
        failing command is reported after all the others were applied.
        """
        local = self._local
        if local.iter_depth or local.system is not None:
            raise EcsError("flush() cannot run while a system or a query loop is active")
        if len(self._queue):  # most sync points have nothing queued
            self._queue.apply(self.storage, self.write_tick)
        if self._reactions is not None:
            self._react()

    # ---------------------------------------------------------------- systems
    def open_stage(self, systems: int) -> None:
        """A schedule stage of `systems` systems starts: until close_stage, spawns take the ids
        of the running system's place in it (`lane`, see stage_ids.py)."""
        self._stage = (systems, None)

    def close_stage(self, queues: Iterable[CommandQueue]) -> None:
        """The stage's systems have run: the ids none of them took go back, and what they queued
        (`queues`, in declared order) joins the world's queue for the sync point that follows."""
        stage, self._stage = self._stage, None
        if stage is not None and stage[1] is not None:
            stage[1].close()
        self.join_commands(queues)

    def run_system(
        self, system: RunningSystem, dt: float, queue: CommandQueue | None = None, lane: int | None = None
    ) -> None:
        """Run one system with its own change tick; structural changes wait for a flush (in
        `queue` when given, for the caller to join). `lane`: its place in the open stage."""
        if self._local.system is not None:
            raise EcsError(f"system {system.name} started inside system {self._local.system.name}")
        self.tick += 1
        run_as(self, self._local, system, dt, self.tick, queue, lane)

    def run_systems_together(
        self,
        systems: Sequence[RunningSystem],
        dt: float,
        spread: Any,
        queues: Sequence[CommandQueue],
        lanes: Sequence[int] | None = None,
    ) -> None:
        """Run systems whose declared access does not conflict at the same time:
        `spread(job, range(len(systems)))` runs the jobs (JobPool.map). Each gets its change tick
        (in the order given) and queues its structural changes in its own `queues[i]`, which the
        caller joins in its declared order (`join_commands`), so the result does not depend on
        which thread finishes first; `lanes`: their places in the open stage (for their ids). A
        system's error is raised as it was, after all finished."""
        if self._local.system is not None:
            raise EcsError(f"systems started inside system {self._local.system.name}")
        ticks = [self.tick + 1 + i for i in range(len(systems))]
        self.tick += len(systems)
        single, self._local = self._local, ThreadRunning()  # each thread its own, for the group
        try:
            run_group(self, self._local, systems, dt, spread, queues, lanes or range(len(systems)), ticks)
        finally:
            self._local = single

    def join_commands(self, queues: Iterable[CommandQueue]) -> None:
        """Append queued structural changes (run_systems_together's) to the world's, in order."""
        for queue in queues:
            if queue.commands:  # most systems queue nothing: skip them without a call
                self._queue.extend(queue)

    def _reserve(self, n: int) -> np.ndarray:
        """n new ids for a deferred spawn; while a schedule stage runs, the running system's
        (stage_ids.py: the same whatever order the stage's systems run in)."""
        index = self.storage.index
        with self._ids_lock:
            if self._stage is None:
                ids = index.allocate(n)
            else:
                systems, plan = self._stage
                if plan is None:  # made at the first spawn: most stages spawn nothing
                    plan = StageIds(index, systems)
                    self._stage = (systems, plan)
                lane = self._local.lane
                ids = plan.take(0 if lane is None else lane, n)
            index.reserve(ids)
        return ids
