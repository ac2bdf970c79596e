"""Systems and the schedule that runs them each frame, in stated order, with sync points.

A parallel schedule (`Schedule(parallel=True)`, with a JobPool resource in the world) runs the
systems of one stage whose declared access does not conflict at the same time on the pool's
threads: two systems conflict when one writes a type the other reads or writes, or when either
is undeclared (reads or writes None) or `exclusive`. A system runs after every earlier system it
conflicts with (its "level" is one more than theirs), so conflicting systems keep their declared
order; structural changes are applied at the stage's sync point in declared order too. Declare
resources and event types the same way as components (`reads=[RenderOrigin]`): access the
schedule cannot see is a data race in a parallel stage. Only numba kernels and large NumPy calls
release the GIL, so only such systems gain.

In sequence as in parallel, each system of a stage queues its structural changes on its own (a
change it asks for does not see what another system queued; one that names an entity an earlier
system destroyed is left out at the sync point) and its spawns take the ids of its place in the
stage (stage_ids.py), so a parallel stage gives the sequential result, entity ids included.
Inside a system that declares its access, `world.get` and `change_stamp` are checked as queries
are, and `world.locate` (a whole table, open to any write) is refused.

A system may have a run condition (`run_if`, as Bevy's): a function of the world, asked just
before the system would run; False skips it, and its change tick stays where it was, so its next
run sees every change since its last one. `any_with(A, B)` (some entity has A and B) is the usual
one: the stock systems skip a frame's call when no entity has what they work on.

A schedule with a `timer` (see SystemTimer: the app's profiler sets one while someone looks at
the figures) reports each system's run, with the clock read around it on the thread that ran it;
without one (the default) a stage pays one attribute test and nothing per system.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from time import perf_counter_ns
from typing import Any, Protocol

from ..jobs import JobPool
from .commands import CommandQueue
from .errors import EcsError
from .schema import schema_of
from .states import StateKinds, Transitions, checked_value
from .timestep import Interpolation
from .world import World


class FixedClock(Protocol):
    """How many fixed steps a frame takes, and where it lies between the last two (see
    timestep.FixedTimestep)."""

    step: float

    @property
    def alpha(self) -> float: ...

    def advance(self, frame_dt: float) -> int: ...


class SystemTimer(Protocol):
    """What a schedule reports each system's run to, from the thread that ran it."""

    def system(self, name: str, start_ns: int, end_ns: int) -> None: ...


def _types(items: Iterable[type] | None) -> frozenset[type] | None:
    if items is None:
        return None
    return frozenset(schema_of(t) for t in items)


RunCondition = Callable[[World], bool]


class AnyWith:
    """A run condition: some entity has every type of one of the groups (`any_with(A, B)`; `|`
    adds a group). Reads only the world's tables (no system access is checked); the answer is
    kept while the world's structure stays the same (a frame asks for the price of a lookup)."""

    def __init__(self, *groups: tuple[type, ...]) -> None:
        if not groups or not all(groups):
            raise ValueError("any_with needs at least one component type")
        self.groups = groups

    def __call__(self, world: World) -> bool:
        # ecs/structural.py's answers, kept under this condition itself (inline: asked per system
        # and frame)
        kept = world.storage.answers
        answer = kept.get(self)
        if answer is None:
            answer = kept[self] = any(world.query(*group, write=()).count() for group in self.groups)
        return answer

    def __or__(self, other: AnyWith) -> AnyWith:
        return AnyWith(*self.groups, *other.groups)

    def __repr__(self) -> str:
        return " | ".join(f"any_with({', '.join(t.__name__ for t in g)})" for g in self.groups)


def any_with(*types: type) -> AnyWith:
    """The run condition "some entity has all of `types`"."""
    return AnyWith(tuple(types))


class AllOf:
    """Run conditions that must all hold (a system's own and the one `Schedule.add` gives)."""

    def __init__(self, *conditions: RunCondition) -> None:
        self.conditions = conditions

    def __call__(self, world: World) -> bool:
        return all(condition(world) for condition in self.conditions)

    def __repr__(self) -> str:
        return " and ".join(map(repr, self.conditions))


class System:
    """A unit of per-frame work that declares the components it reads and writes.

    Subclass and override `run(world, dt)`, or wrap a function with `@system(...)`. Inside a
    run, queries hand out read-only views of the components only read, writable views of the
    ones written (which marks them changed), and reject undeclared components. `reads` and
    `writes` of None mean "anything" (an undeclared plain function). `run_if`: the run
    condition (see the module), None to run every time.
    """

    reads: frozenset[type] | None = frozenset()
    writes: frozenset[type] | None = frozenset()
    last_run_tick: int = 0
    exclusive: bool = False  # never run alongside another system (a parallel schedule)
    run_if: RunCondition | None = None

    def __init__(
        self,
        reads: Iterable[type] | None = (),
        writes: Iterable[type] | None = (),
        name: str | None = None,
        run_if: RunCondition | None = None,
    ) -> None:
        self.reads = _types(reads)
        self.writes = _types(writes)
        self.name = name or type(self).__name__
        self.last_run_tick = 0
        if run_if is not None and not callable(run_if):
            raise TypeError(f"system {self.name}: run_if must be a function of the world, got {run_if!r}")
        self.run_if = run_if

    def run(self, world: World, dt: float) -> None:
        raise NotImplementedError

    def __repr__(self) -> str:
        def names(s: frozenset[type] | None) -> str:
            return "any" if s is None else "[" + ", ".join(sorted(t.__name__ for t in s)) + "]"

        return f"<system {self.name} reads={names(self.reads)} writes={names(self.writes)}>"


class FunctionSystem(System):
    def __init__(
        self,
        fn: Callable[[World, float], Any],
        reads: Iterable[type] | None = (),
        writes: Iterable[type] | None = (),
        name: str | None = None,
        run_if: RunCondition | None = None,
    ) -> None:
        super().__init__(reads, writes, name or getattr(fn, "__name__", "system"), run_if)
        self.fn = fn

    def run(self, world: World, dt: float) -> None:
        self.fn(world, dt)


def system(
    reads: Iterable[type] = (),
    writes: Iterable[type] = (),
    name: str | None = None,
    run_if: RunCondition | None = None,
) -> Callable[[Callable[[World, float], Any]], FunctionSystem]:
    """Decorator: `@system(reads=[Velocity], writes=[Transform])` over `def f(world, dt)`."""

    def wrap(fn: Callable[[World, float], Any]) -> FunctionSystem:
        return FunctionSystem(fn, reads, writes, name, run_if)

    return wrap


def as_system(obj: System | Callable[[World, float], Any]) -> System:
    if isinstance(obj, System):
        return obj
    if callable(obj):
        return FunctionSystem(obj, reads=None, writes=None)
    raise TypeError(f"not a system: {obj!r}")


def conflict(a: System, b: System) -> bool:
    """Whether two systems may not run at the same time (see the module docstring)."""
    if a.exclusive or b.exclusive or a.reads is None or a.writes is None or b.reads is None or b.writes is None:
        return True
    return bool(a.writes & (b.reads | b.writes)) or bool(b.writes & a.reads)


def levels(systems: Sequence[System]) -> list[list[int]]:
    """The indices of `systems` grouped by level: each system one level after the last earlier
    system it conflicts with; a level's systems may run at the same time."""
    level: list[int] = []
    for i, s in enumerate(systems):
        level.append(1 + max((level[j] for j in range(i) if conflict(systems[j], s)), default=-1))
    groups: list[list[int]] = [[] for _ in range(max(level, default=-1) + 1)]
    for i, n in enumerate(level):
        groups[n].append(i)
    return groups


class Schedule:
    """Stages run in order; systems in a stage run in the order added; after every stage comes a
    sync point where deferred structural changes (spawn, destroy, add, remove) are applied, and
    after every frame the event channels turn over. `parallel=True`: see the module docstring.
    `timer`: where each system's run is reported (None: not timed)."""

    timer: SystemTimer | None = None

    def __init__(self, stages: Iterable[str] = ("update", "post_update"), parallel: bool = False) -> None:
        self.stages: dict[str, list[System]] = {name: [] for name in stages}
        if not self.stages:
            raise ValueError("a schedule needs at least one stage")
        self.parallel = parallel
        self._levels: dict[str, tuple[tuple[int, ...], list[list[int]]]] = {}  # per stage, by its systems
        # per stage, one per system (made as they are added): each system's structural changes
        self._queues: dict[str, list[CommandQueue]] = {name: [] for name in self.stages}
        self.transitions = Transitions()  # OnEnter and OnExit systems (states.py)

    def add(
        self, obj: System | Callable[[World, float], Any], stage: str | None = None, run_if: RunCondition | None = None
    ) -> System:
        """Add a system to a stage (the first by default); `run_if`: a run condition, added to
        the system's own if it has one (both must hold)."""
        stage = stage or next(iter(self.stages))
        if stage not in self.stages:
            raise ValueError(f"unknown stage {stage!r}; stages are {list(self.stages)}")
        sys_ = self._new(obj, run_if)
        self.stages[stage].append(sys_)
        self._queues[stage].append(CommandQueue())
        return sys_

    def _new(self, obj: System | Callable[[World, float], Any], run_if: RunCondition | None) -> System:
        sys_ = as_system(obj)
        if any(s is sys_ for systems in self.stages.values() for s in systems) or any(
            s is sys_ for s in self.transitions.systems()
        ):
            raise ValueError(f"system {sys_.name} is already scheduled")
        if run_if is not None:
            if not callable(run_if):
                raise TypeError(f"system {sys_.name}: run_if must be a function of the world, got {run_if!r}")
            sys_.run_if = run_if if sys_.run_if is None else AllOf(sys_.run_if, run_if)
        return sys_

    def on_enter(self, state: Any, obj: System | Callable[[World, float], Any]) -> System:
        """Run a system once each time the world's state becomes `state` (states.py)."""
        sys_ = self._new(obj, None)
        self.transitions.on_enter.setdefault(checked_value(state, "on_enter"), []).append(sys_)
        return sys_

    def on_exit(self, state: Any, obj: System | Callable[[World, float], Any]) -> System:
        """Run a system once each time the world's state leaves `state` (states.py)."""
        sys_ = self._new(obj, None)
        self.transitions.on_exit.setdefault(checked_value(state, "on_exit"), []).append(sys_)
        return sys_

    def order(self) -> list[tuple[str, list[str]]]:
        return [(stage, [s.name for s in systems]) for stage, systems in self.stages.items()]

    def groups(self, stage: str) -> list[list[str]]:
        """The names of a stage's systems by level: those of one level may run together."""
        systems = self.stages[stage]
        return [[systems[i].name for i in group] for group in levels(systems)]

    def _run_stage(self, world: World, name: str, dt: float) -> None:
        """The stage's systems, then its sync point. Sequential or parallel, each system queues
        its structural changes on its own and spawns the ids of its place in the stage, so the
        result is the same in both (see the module)."""
        systems, queues = self.stages[name], self._queues[name]
        pool = world.resources.get(JobPool) if self.parallel else None
        count = len(systems)
        several = count > 1  # one system alone takes the ids a plain spawn would
        if several:
            world.open_stage(count)
        try:
            if pool is None or pool.threads < 2 or not several:
                timer = self.timer
                for i, sys_ in enumerate(systems):
                    if sys_.run_if is None or sys_.run_if(world):
                        if timer is None:
                            world.run_system(sys_, dt, queues[i], i)
                            continue
                        start = perf_counter_ns()
                        try:
                            world.run_system(sys_, dt, queues[i], i)
                        finally:
                            timer.system(sys_.name, start, perf_counter_ns())
            else:
                self._run_together(world, name, systems, dt, pool, queues)
        finally:
            world.close_stage(queues)
        world.flush()

    def _run_together(
        self, world: World, name: str, systems: list[System], dt: float, pool: JobPool, queues: list[CommandQueue]
    ) -> None:
        key = tuple(id(s) for s in systems)
        cached = self._levels.get(name)
        if cached is None or cached[0] != key:
            cached = self._levels[name] = (key, levels(systems))
        for everyone in cached[1]:
            group = [i for i in everyone if _due(systems[i], world)]
            if not group:
                continue
            chosen = [systems[i] for i in group]
            spread = pool.map if len(chosen) > 1 else _inline  # alone: its own jobs may spread
            if self.timer is not None:
                spread = _timed_spread(spread, chosen, self.timer)
            world.run_systems_together(chosen, dt, spread, [queues[i] for i in group], group)

    def run_frame(
        self, world: World, frame_dt: float, clock: FixedClock, fixed_stage: str = "fixed", max_frame_dt: float = 0.1
    ) -> int:
        """One frame with a fixed-step stage: `fixed_stage` runs clock.advance(frame_dt) times
        with dt = clock.step; the other stages run once with frame_dt, at most `max_frame_dt` (a
        hitch must not fling a per-frame camera); the Interpolation resource gets the frame's
        alpha. What a fixed step must remember for interpolated drawing (the stock
        systems.SnapshotSystem) is a system at the head of the fixed stage. `clock` is a
        timestep.FixedTimestep. Returns the steps run."""
        if fixed_stage not in self.stages:
            raise ValueError(f"unknown stage {fixed_stage!r}; stages are {list(self.stages)}")
        if world.deferring:
            raise EcsError("Schedule.run_frame() cannot be called from inside a system or a query loop")
        world.flush()
        kinds = world.resources.get(StateKinds)
        if kinds is not None:  # the state transition step: first in the frame (states.py)
            self.transitions.step(world, kinds, min(float(frame_dt), max_frame_dt))
        steps = clock.advance(frame_dt)
        for _ in range(steps):
            self._run_stage(world, fixed_stage, clock.step)
        kept = world.resources.get(Interpolation)
        if type(kept) is Interpolation:
            kept.alpha = clock.alpha  # the frame's, in the resource the systems know
        else:
            world.resources[Interpolation] = Interpolation(clock.alpha)
        variable_dt = min(float(frame_dt), max_frame_dt)
        for name in self.stages:
            if name != fixed_stage:
                self._run_stage(world, name, variable_dt)
        world.update_events()
        return steps

    def run(self, world: World, dt: float) -> None:
        if world.deferring:
            raise EcsError("Schedule.run() cannot be called from inside a system or a query loop")
        world.flush()
        kinds = world.resources.get(StateKinds)
        if kinds is not None:  # the state transition step: first in the frame (states.py)
            self.transitions.step(world, kinds, dt)
        for name in self.stages:
            self._run_stage(world, name, dt)
        world.update_events()


def _inline(fn: Callable[[Any], Any], chunks: Iterable[Any]) -> list[Any]:
    return [fn(chunk) for chunk in chunks]


def _timed_spread(spread: Callable[..., Any], systems: list[System], timer: SystemTimer) -> Callable[..., Any]:
    """`spread` with each system's job timed on the thread that runs it."""

    def spread_timed(job: Callable[[int], None], indices: range) -> Any:
        def system_job(i: int) -> None:
            start = perf_counter_ns()
            try:
                job(i)
            finally:
                timer.system(systems[i].name, start, perf_counter_ns())

        return spread(system_job, indices)

    return spread_timed


def _due(sys_: System, world: World) -> bool:
    """Whether the system runs now (its run condition, if any)."""
    condition = sys_.run_if
    return condition is None or bool(condition(world))
