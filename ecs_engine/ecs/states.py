"""States (as Bevy's): a game's mode as an Enum value in a resource, systems that run only in
some states, and systems run once on entering or leaving one.

    class GameState(Enum):
        MENU = 1
        PLAYING = 2

    init_state(world, GameState.MENU)                  # State[GameState] and NextState[GameState]
    schedule.add(move, run_if=in_state(GameState.PLAYING))
    schedule.on_enter(GameState.PLAYING, spawn_level)   # once per transition into it
    schedule.on_exit(GameState.PLAYING, clear_level)
    request_state(world, GameState.PLAYING)             # from a system declaring writes=[NextState[GameState]]

The transition step is the first thing of a frame (`Schedule.run` and `run_frame`, after the sync
point that opens it): for each state (in the order initialised) with a request pending, the
OnExit systems of the old value run, then a sync point, the value changes, the OnEnter systems
of the new one run, then a sync point. So every system of a frame sees one state, and a request
made during frame N is seen from frame N+1 on. The first step enters the initial state (its
OnEnter systems run). One transition per state per frame: a request made by an OnEnter system
waits for the next frame; requesting the current value does nothing; the last request of a
frame wins (systems that request declare `writes=[NextState[Kind]]`, so a parallel schedule
runs them in declared order).
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from typing import Any, ClassVar, Generic, TypeVar

from .commands import CommandQueue
from .errors import AccessError, EcsError
from .running import RunningSystem
from .schema import schema_of

Kind = type[enum.Enum]
E = TypeVar("E", bound=enum.Enum)


def checked_value(value: Any, what: str, kind: Kind | None = None) -> enum.Enum:
    """A state value: a member of an Enum class (of `kind` when given)."""
    if kind is not None and not isinstance(value, kind):
        got = f"{type(value).__name__}.{value.name}" if isinstance(value, enum.Enum) else f"{value!r}"
        raise TypeError(f"{what} takes a {kind.__name__} member, got {got}")
    if not isinstance(value, enum.Enum):
        raise TypeError(f"{what} takes a member of an Enum class (a state), got {type(value).__name__} {value!r}")
    return value


_made: dict[tuple[type, Kind], type] = {}


def of_kind(cls: type, kind: Kind) -> Any:
    """`State[GameState]`: a class of its own per Enum, made once (a resource key and an access
    token for declared access); generic for type checkers."""
    if not (isinstance(kind, type) and issubclass(kind, enum.Enum)):
        raise TypeError(f"{cls.__name__}[...] takes an Enum class, got {kind!r}")
    made = _made.get((cls, kind))
    if made is None:
        name = f"{cls.__name__}[{kind.__name__}]"
        made = _made[(cls, kind)] = type(name, (cls,), {"kind": kind, "__qualname__": name})
    return made


class State(Generic[E]):
    """The resource holding a state's current value: `world.resources[State[GameState]].get()`."""

    kind: ClassVar[Kind]

    def __class_getitem__(cls, kind: Kind) -> Any:
        return of_kind(cls, kind)

    def __init__(self, value: enum.Enum) -> None:
        if not hasattr(type(self), "kind"):
            raise TypeError("make a state with init_state(world, Kind.VALUE), or State[Kind](value)")
        self.current = checked_value(value, f"State[{self.kind.__name__}]", self.kind)
        self.previous: enum.Enum | None = None
        self.entered = False  # the initial value's OnEnter systems ran

    def get(self) -> enum.Enum:
        return self.current

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.current.name}>"


class NextState(Generic[E]):
    """The resource holding a state's requested value, applied at the next frame's transition step."""

    kind: ClassVar[Kind]

    def __class_getitem__(cls, kind: Kind) -> Any:
        return of_kind(cls, kind)

    def __init__(self, host: Any = None) -> None:
        self.host = host  # the world: whose running system must declare the request
        self.pending: enum.Enum | None = None

    def set(self, value: enum.Enum) -> None:
        value = checked_value(value, f"NextState[{self.kind.__name__}].set", self.kind)
        system = self.host.running_system() if self.host is not None else None
        if system is not None and system.writes is not None and schema_of(type(self)) not in system.writes:
            raise AccessError(
                f"system {system.name} requests a {self.kind.__name__} state but does not declare "
                f"writes=[NextState[{self.kind.__name__}]]"
            )
        self.pending = value


class StateKinds:
    """The world's states, in the order initialised (the resource the transition step reads)."""

    def __init__(self) -> None:
        self.kinds: list[Kind] = []


def init_state(world: Any, initial: enum.Enum) -> State:
    """Give the world a state, starting at `initial` (entered at the next frame's transition step)."""
    kind = type(checked_value(initial, "init_state"))
    kinds = world.resources.get(StateKinds)
    if kinds is None:
        kinds = world.resources[StateKinds] = StateKinds()
    if kind in kinds.kinds:
        raise EcsError(f"the world already has a {kind.__name__} state (now {current_state(world, kind).name})")
    state = world.resources[of_kind(State, kind)] = of_kind(State, kind)(initial)
    world.resources[of_kind(NextState, kind)] = of_kind(NextState, kind)(world)
    kinds.kinds.append(kind)
    return state


def _state(world: Any, kind: Kind, what: str) -> State:
    state = world.resources.get(of_kind(State, kind))
    if state is None:
        raise EcsError(f"{what}: the world has no {kind.__name__} state (init_state(world, {kind.__name__}.<first>))")
    return state


def current_state(world: Any, kind: Kind) -> enum.Enum:
    return _state(world, kind, f"current_state({kind.__name__})").current


def request_state(world: Any, value: enum.Enum) -> None:
    """Ask for a transition to `value` at the start of the next frame (see the module)."""
    kind = type(checked_value(value, "request_state"))
    _state(world, kind, f"request_state({kind.__name__}.{value.name})")
    world.resources[of_kind(NextState, kind)].set(value)


class InState:
    """The run condition "the state is one of these values" (`in_state(GameState.PLAYING)`): a
    dictionary lookup and a set test, asked every frame."""

    def __init__(self, *values: enum.Enum) -> None:
        if not values:
            raise TypeError("in_state needs at least one state value")
        kind = type(checked_value(values[0], "in_state"))
        for value in values[1:]:
            checked_value(value, "in_state", kind)
        self.kind, self.values, self.key = kind, frozenset(values), of_kind(State, kind)

    def __call__(self, world: Any) -> bool:
        state = world.resources.get(self.key)
        if state is None:
            _state(world, self.kind, repr(self))
        return state.current in self.values

    def __repr__(self) -> str:
        return f"in_state({', '.join(f'{self.kind.__name__}.{v.name}' for v in sorted(self.values, key=str))})"


def in_state(*values: enum.Enum) -> InState:
    """The run condition "the world's state is one of `values`" (all of one Enum)."""
    return InState(*values)


class Transitions:
    """A schedule's OnEnter and OnExit systems, and the step that runs them (Schedule calls it)."""

    def __init__(self) -> None:
        self.on_enter: dict[enum.Enum, list[Any]] = {}
        self.on_exit: dict[enum.Enum, list[Any]] = {}

    def systems(self) -> list[Any]:
        return [s for table in (self.on_enter, self.on_exit) for systems in table.values() for s in systems]

    def step(self, world: Any, kinds: StateKinds, dt: float) -> None:
        for kind in kinds.kinds:
            state: State = world.resources[of_kind(State, kind)]
            if not state.entered:
                state.entered = True
                run_systems(world, self.on_enter.get(state.current, ()), dt)
            request: NextState = world.resources[of_kind(NextState, kind)]
            value, request.pending = request.pending, None
            if value is None or value is state.current:
                continue
            run_systems(world, self.on_exit.get(state.current, ()), dt)
            state.previous, state.current = state.current, value
            run_systems(world, self.on_enter.get(value, ()), dt)


def run_systems(world: Any, systems: Sequence[RunningSystem], dt: float) -> None:
    """Systems one after another as a schedule stage runs them (each queues its structural
    changes on its own, its spawns take its place's ids), then the sync point."""
    if not systems:
        return
    queues = [CommandQueue() for _ in systems]
    if len(systems) > 1:  # one alone takes the ids a plain spawn would (as Schedule does)
        world.open_stage(len(systems))
    try:
        for i, system in enumerate(systems):
            condition = getattr(system, "run_if", None)
            if condition is None or condition(world):
                world.run_system(system, dt, queues[i], i)
    finally:
        world.close_stage(queues)
    world.flush()
