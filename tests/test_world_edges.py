"""Edge cases of the World API found by testing it as a new user would (issue 19): each test
failed before its fix."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import Component, Field, World
from ecs_engine.components import Camera, Transform


class Tagged(Component):
    tag = Field(object)
    k = Field(np.int16)


class B(Component):
    v = Field(np.int32)


class A(Component):
    v = Field(np.int32)


def test_get_returns_object_fields_as_stored():
    w = World()
    e = w.spawn(Tagged(tag="hi", k=3))
    got = w.get(e, Tagged)
    assert got.tag == "hi" and got.k == 3
    box = {"a": 1}
    assert w.get(w.spawn(Tagged(tag=box)), Tagged).tag is box  # the object itself


@pytest.mark.parametrize("n", [1, 2, 3])
def test_one_object_value_is_shared_by_every_row_for_every_n(n):
    """The rule: a NumPy object array of shape (n,) is one value per row; anything else (a
    string, a list, None) is one value for all rows, whatever n is."""
    w = World()
    for shared in ("abc", ["x"], None, ("p", "q")):
        ids = w.spawn_batch(n, Tagged(tag=shared, k=1))
        assert [w.get(int(e), Tagged).tag for e in ids] == [shared] * n
    per_row = np.empty(n, dtype=object)
    per_row[:] = [f"row{i}" for i in range(n)]
    ids = w.spawn_batch(n, Tagged(tag=per_row))
    assert [w.get(int(e), Tagged).tag for e in ids] == [f"row{i}" for i in range(n)]
    w.set(ids, Tagged, tag=["same", "list"])
    assert all(w.get(int(e), Tagged).tag == ["same", "list"] for e in ids)
    assert w.get(int(w.spawn_batch(n, Tagged(k=1))[0]), Tagged).tag is None  # the default, shared


def test_an_object_default_that_is_a_sequence_fills_every_row():
    class Labels(Component):
        names = Field(object, default=[])

    w = World()
    ids = w.spawn_batch(3, Labels())
    assert [w.get(int(e), Labels).names for e in ids] == [[], [], []]
    e = w.spawn(A(v=1))
    w.add(e, Labels())  # the row moves: the new column gets the default
    assert w.get(e, Labels).names == []


def test_huge_and_tiny_finite_quaternions_are_normalised_without_overflow():
    w = World()
    for q in [(1e200, 0, 0, 0), (0, 3e300, 4e300, 0), (-1e308, 1e308, 1e308, -1e308)]:
        r = w.get(w.spawn(Transform(rotation=q)), Transform).rotation
        assert np.isclose(np.linalg.norm(r), 1.0) and np.all(np.isfinite(r))
    assert np.allclose(w.get(w.spawn(Transform(rotation=(0, 3e300, 4e300, 0))), Transform).rotation, (0, 0.6, 0.8, 0))
    for nothing in [(0.0, 0.0, 0.0, 0.0), (1e-160, 1e-160, 0.0, 0.0)]:  # too short to have a direction
        with pytest.raises(ValueError, match="non-zero length"):
            w.spawn(Transform(rotation=nothing))


def test_a_deferred_partial_set_is_checked_against_the_other_fields_when_applied():
    w = World()
    with pytest.raises(ValueError, match=r"Camera\.near \(50\.0\) must be less than Camera\.far \(10\.0\)"):
        with w.deferred():
            c = w.spawn(Camera(near=0.1, far=10))
            w.set(c, Camera, near=50.0)
    assert w.get(c, Camera).near == pytest.approx(0.1)  # the failed set changed nothing
    with pytest.raises(ValueError, match=r"must be less than Camera\.far"):
        with w.deferred():
            d = w.spawn(Transform())
            w.add(d, Camera(near=0.1, far=10))
            w.set(d, Camera, near=50.0)
    assert w.get(d, Camera).near == pytest.approx(0.1) and w.get(d, Camera).far == 10


@pytest.mark.parametrize("call", ["add", "set", "remove", "destroy"])
def test_an_empty_id_array_is_a_no_op(call):
    w = World()
    e = w.spawn(A(v=1))
    empty = np.array([], dtype=np.int64)
    {
        "add": lambda: w.add(empty, B(v=1)),
        "set": lambda: w.set(empty, A, v=3),
        "remove": lambda: w.remove(empty, A),
        "destroy": lambda: w.destroy(empty),
    }[call]()
    assert len(w) == 1 and w.get(e, A).v == 1 and not w.has(e, B)
    with pytest.raises(TypeError, match="not the class itself"):
        w.add(empty, B)  # the value is still checked


def test_in_a_query_loop_the_later_of_a_queued_add_and_a_set_wins():
    w = World()
    e = w.spawn(A(v=1), B(v=0))
    for _ in w.query(A):
        w.add(e, B(v=1))  # queued: structural while iterating
        w.set(e, B(v=2))  # must not jump ahead of the queued add
    assert w.get(e, B).v == 2
    f = w.spawn(A(v=1))
    for _ in w.query(A, write=()):
        w.set(f, A, v=5)  # nothing queued for f: written at once, as before
        assert w.get(f, A).v == 5
        break


def test_entity_ids_are_integers_everywhere():
    w = World()
    e = w.spawn(A(v=1))
    for call in (
        lambda x: w.get(x, A),
        lambda x: w.has(x, A),
        w.is_alive,
        w.components,
        w.destroy,
        lambda x: w.set(x, A, v=2),
        lambda x: w.change_stamp(x, A),
    ):
        for bad in (float(e), True, str(e)):
            with pytest.raises(TypeError, match="must be integers"):
                call(bad)
    assert w.get(np.int64(e), A).v == 1 and w.is_alive(np.uint64(e))


def test_spawn_batch_of_zero_rows_with_array_values():
    """An empty batch with per-row arrays (shape (0, 3)) spawns nothing and does not fail."""
    import numpy as np

    from ecs_engine import World
    from ecs_engine.components import PointLight, Transform

    world = World()
    ids = world.spawn_batch(0, Transform(position=np.zeros((0, 3))), PointLight(color=np.zeros((0, 3), np.float32)))
    assert len(ids) == 0 and len(world) == 0
