"""Systems and the schedule that runs them each frame, in stated order, with sync points."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any, Protocol

from .errors import EcsError
from .schema import schema_of
from .timestep import Interpolation
from .world import World


class FixedClock(Protocol):
    """How many fixed steps a frame takes, and where it lies between the last two (see
    timestep.FixedTimestep)."""

    step: float

    @property
    def alpha(self) -> float: ...

    def advance(self, frame_dt: float) -> int: ...


def _types(items: Iterable[type] | None) -> frozenset[type] | None:
    if items is None:
        return None
    return frozenset(schema_of(t) for t in items)


class System:
    """A unit of per-frame work that declares the components it reads and writes.

    Subclass and override `run(world, dt)`, or wrap a function with `@system(...)`. Inside a
    run, queries hand out read-only views of the components only read, writable views of the
    ones written (which marks them changed), and reject undeclared components. `reads` and
    `writes` of None mean "anything" (an undeclared plain function).
    """

    reads: frozenset[type] | None = frozenset()
    writes: frozenset[type] | None = frozenset()
    last_run_tick: int = 0

    def __init__(
        self, reads: Iterable[type] | None = (), writes: Iterable[type] | None = (), name: str | None = None
    ) -> None:
        self.reads = _types(reads)
        self.writes = _types(writes)
        self.name = name or type(self).__name__
        self.last_run_tick = 0

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
    ) -> None:
        super().__init__(reads, writes, name or getattr(fn, "__name__", "system"))
        self.fn = fn

    def run(self, world: World, dt: float) -> None:
        self.fn(world, dt)


def system(
    reads: Iterable[type] = (), writes: Iterable[type] = (), name: str | None = None
) -> Callable[[Callable[[World, float], Any]], FunctionSystem]:
    """Decorator: `@system(reads=[Velocity], writes=[Transform])` over `def f(world, dt)`."""

    def wrap(fn: Callable[[World, float], Any]) -> FunctionSystem:
        return FunctionSystem(fn, reads, writes, name)

    return wrap


def as_system(obj: System | Callable[[World, float], Any]) -> System:
    if isinstance(obj, System):
        return obj
    if callable(obj):
        return FunctionSystem(obj, reads=None, writes=None)
    raise TypeError(f"not a system: {obj!r}")


class Schedule:
    """Stages run in order; systems in a stage run in the order added; after every stage comes a
    sync point where deferred structural changes (spawn, destroy, add, remove) are applied."""

    def __init__(self, stages: Iterable[str] = ("update", "post_update")) -> None:
        self.stages: dict[str, list[System]] = {name: [] for name in stages}
        if not self.stages:
            raise ValueError("a schedule needs at least one stage")

    def add(self, obj: System | Callable[[World, float], Any], stage: str | None = None) -> System:
        stage = stage or next(iter(self.stages))
        if stage not in self.stages:
            raise ValueError(f"unknown stage {stage!r}; stages are {list(self.stages)}")
        sys_ = as_system(obj)
        if any(s is sys_ for systems in self.stages.values() for s in systems):
            raise ValueError(f"system {sys_.name} is already scheduled")
        self.stages[stage].append(sys_)
        return sys_

    def order(self) -> list[tuple[str, list[str]]]:
        return [(stage, [s.name for s in systems]) for stage, systems in self.stages.items()]

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
        steps = clock.advance(frame_dt)
        for _ in range(steps):
            _run_stage(world, self.stages[fixed_stage], clock.step)
        world.resources[Interpolation] = Interpolation(clock.alpha)
        variable_dt = min(float(frame_dt), max_frame_dt)
        for name, systems in self.stages.items():
            if name != fixed_stage:
                _run_stage(world, systems, variable_dt)
        return steps

    def run(self, world: World, dt: float) -> None:
        if world.deferring:
            raise EcsError("Schedule.run() cannot be called from inside a system or a query loop")
        world.flush()
        for systems in self.stages.values():
            _run_stage(world, systems, dt)


def _run_stage(world: World, systems: list[System], dt: float) -> None:
    """A stage's systems in order, then the sync point (deferred structural changes applied)."""
    for sys_ in systems:
        world.run_system(sys_, dt)
    world.flush()
