"""Undo and redo for the editor's edits: each step is the component values before and after an
edit of one entity, applied back through the World API (so the world's checks still run).

A gizmo drag or a slider moves a value many times a second; `begin(key)` ... `end()` make those
one step (the values when the drag began, and when it ended). A step whose entity is gone, or
lacks the component now, is skipped with its reason in `status`, never raised: the editor keeps
working. Steps that cannot be undone (spawns, destroys: a destroyed id never comes back) are not
recorded; `forget()` clears the history when the world is replaced.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..ecs.errors import EcsError
from ..ecs.world import World

LIMIT = 200  # steps kept


@dataclass
class Step:
    entity: int
    component: type
    before: dict[str, Any]
    after: dict[str, Any] = field(default_factory=dict)


def _fields(world: World, entity: int, component: type, names: Any) -> dict[str, Any]:
    value = world.get(entity, component)
    return {name: np.copy(getattr(value, name)) for name in names}


class History:
    def __init__(self) -> None:
        self.undo_steps: list[Step] = []
        self.redo_steps: list[Step] = []
        self._open: tuple[Any, Step] | None = None  # (key, step) of a drag in progress
        self.status = ""

    def set(self, world: World, entity: int, component: type, **fields: Any) -> None:
        """`world.set(entity, component, **fields)` as an undoable step (raises as world.set)."""
        if self._open is not None and self._open[1].entity == entity and self._open[1].component is component:
            step = self._open[1]
            missing = [n for n in fields if n not in step.before]
            step.before.update(_fields(world, entity, component, missing))
            world.set(entity, component, **fields)
            step.after.update({k: np.copy(v) for k, v in fields.items()})
            return
        before = _fields(world, entity, component, fields)
        world.set(entity, component, **fields)
        self._push(Step(entity, component, before, {k: np.copy(v) for k, v in fields.items()}))

    def begin(self, key: Any, world: World, entity: int, component: type) -> None:
        """Edits of `component` of `entity` until `end()` are one step (a drag); `key` names the
        widget, so a new drag elsewhere closes the last."""
        if self._open is not None and self._open[0] == key:
            return
        self.end()
        self._open = (key, Step(entity, component, {}))

    def end(self, key: Any = None) -> None:
        """Close the open step (with `key`: only if it is that widget's)."""
        if self._open is None or (key is not None and self._open[0] != key):
            return
        step = self._open[1]
        self._open = None
        if step.after:
            self._push(step)

    @property
    def dragging(self) -> bool:
        return self._open is not None

    def _push(self, step: Step) -> None:
        self.undo_steps.append(step)
        del self.undo_steps[:-LIMIT]
        self.redo_steps.clear()

    def undo(self, world: World) -> bool:
        self.end()
        return self._move(world, self.undo_steps, self.redo_steps, "before")

    def redo(self, world: World) -> bool:
        self.end()
        return self._move(world, self.redo_steps, self.undo_steps, "after")

    def _move(self, world: World, source: list[Step], target: list[Step], side: str) -> bool:
        self.status = ""
        while source:
            step = source.pop()
            try:
                world.set(step.entity, step.component, **getattr(step, side))
            except (EcsError, ValueError) as exc:  # the entity or its component is gone
                self.status = f"skipped an edit: {exc}"
                continue
            target.append(step)
            return True
        return False

    def forget(self) -> None:
        self.undo_steps.clear()
        self.redo_steps.clear()
        self._open = None
        self.status = ""
