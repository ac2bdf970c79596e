"""The App's systems by name: adding them (startup, per stage, on a state's enter or exit),
replacing one in its place while the game runs, removing and finding them. Every system has a
name unique in the App (a function's own name, a System's `name`, lambdas numbered), and this
keeps where each runs (`_where`: its stage; `_lists`: the list that runs it). Apart from app.py,
which builds the rest of the App and runs it, so that each stays a readable size."""

from __future__ import annotations

from collections.abc import Callable
from enum import Enum
from typing import Any, Self

from ..ecs.schedule import FunctionSystem, RunCondition, Schedule, System
from ..ecs.world import World
from ..errors import UsageError


class AppSystems:
    """Mixed into App (these are its attributes)."""

    schedule: Schedule
    _startup: list[System]
    _where: dict[str, str]  # system name -> its stage
    _lists: dict[str, list[System]]  # system name -> the list that runs it
    _unnamed: int  # lambdas numbered so far

    def add_startup_systems(self, *systems: Any) -> Self:
        """Systems run once when the run opens, in order, before the first frame: the world
        has its Meshes, Window, Time and the plugins' resources by then."""
        for item in systems:
            made = self._system(item, None)
            self._claim(made, "startup", self._startup)
            self._startup.append(made)
        return self

    def add_systems(self, stage: str, *systems: Any, run_if: RunCondition | None = None) -> Self:
        """Systems run every frame in `stage` ("fixed": every fixed step; "update"; then
        "post_update", where the engine computes matrices), in the order added. `run_if`: a
        function of the world; False skips them that frame (e.g. a state's condition)."""
        if stage not in self.schedule.stages:
            raise UsageError(f"unknown stage {stage!r}; an App's stages are {', '.join(self.schedule.stages)}")
        if not systems:
            raise UsageError(f"add_systems({stage!r}) was given no systems")
        for item in systems:
            made = self._system(item, run_if)
            self._claim(made, stage, self.schedule.stages[stage])
            self.schedule.add(made, stage)
        return self

    def replace_system(self, name: str, new: Any) -> System:
        """`new` in the place of the system called `name`, in the same stage (its run condition
        kept unless `new` has one). The world and entities stay; for code changed while the
        game runs."""
        stage = self._where.get(name)
        if stage is None:
            raise UsageError(f"no system named {name!r}; the App has {', '.join(self._where) or 'none'}")
        listed = self._lists[name]
        index = next(i for i, s in enumerate(listed) if s.name == name)
        old = listed[index]
        made = self._system(new, None)
        if made.name != name and made.name in self._where:
            raise UsageError(f"a system named {made.name!r} is already in the App")
        if made.run_if is None:
            made.run_if = old.run_if
        made.last_run_tick = old.last_run_tick  # it sees what changed since the old one last ran
        listed[index] = made
        del self._where[name], self._lists[name]
        self._where[made.name], self._lists[made.name] = stage, listed
        return made

    # --------------------------------------------------- a state's enter and exit (ecs/states.py)
    def on_enter(self, state: Enum, *systems: Any) -> Self:
        """Systems run once each time the state becomes `state` (at the start of a frame)."""
        return self._on_transition("on_enter", state, systems)

    def on_exit(self, state: Enum, *systems: Any) -> Self:
        """Systems run once each time the state leaves `state`."""
        return self._on_transition("on_exit", state, systems)

    def _on_transition(self, when: str, state: Enum, systems: tuple[Any, ...]) -> Self:
        if not systems:
            raise UsageError(f"{when}({state!r}) was given no systems")
        add = getattr(self.schedule, when)
        for item in systems:
            made = self._system(item, None)
            stage = f"{when} {type(state).__name__}.{getattr(state, 'name', state)}"
            self._claim(made, stage, [])
            try:
                as_usage(add, state, made)
            except UsageError:
                del self._where[made.name], self._lists[made.name]
                raise
            self._lists[made.name] = getattr(self.schedule.transitions, when)[state]
        return self

    # ------------------------------------------------------------------ finding, removing
    def remove_system(self, name: str) -> System:
        """Take the system called `name` out of the App (a startup one too); it runs no more."""
        if self._where.pop(name, None) is None:
            raise UsageError(f"no system named {name!r}; the App has {', '.join(self._where) or 'none'}")
        listed = self._lists.pop(name)
        index = next(i for i, s in enumerate(listed) if s.name == name)
        return listed.pop(index)

    def system(self, name: str) -> System:
        """The system called `name` (a startup one too)."""
        if name not in self._where:
            raise UsageError(f"no system named {name!r}; the App has {', '.join(self._where) or 'none'}")
        return next(s for s in self._lists[name] if s.name == name)

    def systems(self) -> dict[str, str]:
        """Every system's name and its stage ("startup" for a startup system)."""
        return dict(self._where)

    # ------------------------------------------------------------------ making, naming
    def _system(self, item: Any, run_if: RunCondition | None) -> System:
        if run_if is not None and not callable(run_if):
            raise UsageError(f"run_if must be a function of the world, not {run_if!r:.80}")
        if isinstance(item, System):
            made = item
        elif callable(item) and not isinstance(item, type):
            made = FunctionSystem(item, reads=None, writes=None, name=self._name_for(item))
        else:
            what = f"the class {item.__qualname__} (pass an instance)" if isinstance(item, type) else f"{item!r:.80}"
            raise UsageError(f"not a system: {what}; a system is a function (world, dt) or a System")
        if run_if is not None:
            made.run_if = run_if if made.run_if is None else _both(made.run_if, run_if)
        return made

    def _name_for(self, fn: Any) -> str:
        """A function's own name; a lambda (or a callable without one) is numbered."""
        name = getattr(fn, "__name__", None)
        if name and name != "<lambda>":
            return str(name)
        self._unnamed += 1
        return f"{name or 'system'}#{self._unnamed}"

    def _claim(self, made: System, stage: str, listed: list[System]) -> None:
        if made.name in self._where:
            other = f"system(name='{made.name}_2')({made.name})" if isinstance(made, FunctionSystem) else "name="
            raise UsageError(
                f"a system named {made.name!r} is already in the App (stage {self._where[made.name]}); "
                f"names are unique: add the second under its own name ({other}), "
                f"or put new code in its place with replace_system({made.name!r}, ...)"
            )
        self._where[made.name], self._lists[made.name] = stage, listed


def as_usage(call: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """The ECS core's TypeError or ValueError for bad input, as the App's one clear UsageError."""
    try:
        return call(*args, **kwargs)
    except (TypeError, ValueError) as exc:
        raise UsageError(str(exc)) from exc


def _both(first: RunCondition, second: RunCondition) -> RunCondition:
    def both(world: World) -> bool:
        return bool(first(world)) and bool(second(world))

    return both
