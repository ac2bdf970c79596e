"""The editor's undo/redo (app/editor_history.py): steps restore exact values, a drag is one
step, a new edit clears redo, a step about a destroyed entity is skipped with a reason."""

from __future__ import annotations

import numpy as np

from ecs_engine import World
from ecs_engine.app.editor_history import History
from ecs_engine.components import PointLight, Transform


def position(world, e):
    return world.get(e, Transform).position.tolist()


def test_undo_and_redo_restore_values_and_a_drag_is_one_step():
    world = World()
    e = world.spawn(Transform(position=(1.0, 2.0, 3.0)), PointLight(intensity=2.0))
    h = History()
    h.set(world, e, Transform, position=np.array([5.0, 0.0, 0.0]))
    h.begin("gizmo", world, e, Transform)
    for x in range(10):  # a drag: ten moves
        h.set(world, e, Transform, position=np.array([float(x), 1.0, 1.0]), scale=np.array([2.0, 2.0, 2.0]))
    h.end()
    h.set(world, e, PointLight, intensity=7.0)
    assert position(world, e) == [9.0, 1.0, 1.0] and len(h.undo_steps) == 3
    assert h.undo(world) and float(world.get(e, PointLight).intensity) == 2.0
    assert h.undo(world) and position(world, e) == [5.0, 0.0, 0.0]
    assert world.get(e, Transform).scale.tolist() == [1.0, 1.0, 1.0]  # the drag's first value
    assert h.undo(world) and position(world, e) == [1.0, 2.0, 3.0]
    assert not h.undo(world)
    assert h.redo(world) and h.redo(world) and position(world, e) == [9.0, 1.0, 1.0]
    h.set(world, e, Transform, position=np.array([0.0, 0.0, 0.0]))
    assert not h.redo(world)  # a new edit clears what could be redone


def test_a_step_about_a_destroyed_entity_is_skipped_with_a_reason():
    world = World()
    a, b = world.spawn(Transform()), world.spawn(Transform())
    h = History()
    h.set(world, a, Transform, position=np.array([1.0, 0.0, 0.0]))
    h.set(world, b, Transform, position=np.array([2.0, 0.0, 0.0]))
    world.destroy(b)
    assert h.undo(world)  # b's step is skipped, a's undone
    assert "skipped an edit" in h.status and str(b) in h.status
    assert position(world, a) == [0.0, 0.0, 0.0]
    h.forget()
    assert not h.undo(world) and not h.redo(world)
