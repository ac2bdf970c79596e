"""Unit tests of the world's entity and component operations."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import (
    Component,
    DeadEntityError,
    EcsError,
    Field,
    MissingComponentError,
    World,
)
from ecs_engine.components import (
    Camera,
    Mesh,
    ModelMatrix,
    PointLight,
    Transform,
    Velocity,
)
from ecs_engine.ecs.entities import INDEX_MASK, MAX_GENERATION


class Health(Component):
    hp = Field(np.float32, default=100.0, finite=True, minimum=0.0)


class Tag(Component):
    pass


def test_spawn_one_and_get_copy():
    w = World()
    e = w.spawn(Transform(position=(1, 2, 3)), Health(hp=5))
    assert w.is_alive(e)
    t = w.get(e, Transform)
    assert t.position.tolist() == [1, 2, 3]
    assert t.rotation.tolist() == [0, 0, 0, 1]
    t.position[0] = 99  # a copy: storage unchanged
    assert w.get(e, Transform).position[0] == 1
    assert w.get(e, Health).hp == 5
    assert set(w.components(e)) == {Transform, Health}
    assert len(w) == 1


def test_ids_are_64_bit_with_generation_and_never_reused():
    w = World()
    a = w.spawn(Tag())
    assert a >> 32 == 1 and a & INDEX_MASK == 0
    w.destroy(a)
    b = w.spawn(Tag())
    assert b & INDEX_MASK == a & INDEX_MASK  # slot reused
    assert b != a and b >> 32 == 2  # with a new generation
    assert not w.is_alive(a)
    with pytest.raises(DeadEntityError, match="not alive"):
        w.get(a, Tag)
    with pytest.raises(DeadEntityError):
        w.destroy(a)


def test_slot_is_retired_when_generation_overflows():
    w = World()
    a = w.spawn(Tag())
    w.storage.index.generation[a & INDEX_MASK] = MAX_GENERATION  # pretend it was reused 2**31 times
    a = (MAX_GENERATION << 32) | (a & INDEX_MASK)
    w.destroy(a)
    b = w.spawn(Tag())
    assert b & INDEX_MASK != a & INDEX_MASK


def test_zero_is_never_an_entity():
    w = World()
    w.spawn(Tag())
    assert not w.is_alive(0)
    with pytest.raises(DeadEntityError):
        w.get(0, Tag)


def test_spawn_batch_shared_and_per_row_values():
    w = World()
    n = 1000
    pos = np.arange(n * 3, dtype=np.float64).reshape(n, 3)
    ids = w.spawn_batch(n, Transform(position=pos), Velocity(linear=(1, 0, 0)), Mesh(handle=7))
    assert ids.dtype == np.int64 and len(np.unique(ids)) == n
    assert len(w) == n
    assert w.get(ids[10], Transform).position.tolist() == pos[10].tolist()
    assert w.get(ids[999], Velocity).linear.tolist() == [1, 0, 0]
    assert w.get(ids[5], Mesh).handle == 7
    # Mesh requires ModelMatrix: added with its defaults
    assert w.has(ids[0], ModelMatrix)
    assert np.array_equal(w.get(ids[0], ModelMatrix).model, np.eye(4))


def test_spawn_batch_zero_and_negative():
    w = World()
    assert len(w.spawn_batch(0, Tag())) == 0
    with pytest.raises(ValueError, match="negative"):
        w.spawn_batch(-1, Tag())


def test_destroy_many_keeps_the_others_intact():
    w = World()
    n = 200
    ids = w.spawn_batch(n, Health(hp=np.arange(n, dtype=np.float32)))
    doomed = ids[::3]
    w.destroy(doomed)
    assert len(w) == n - len(doomed)
    for i, e in enumerate(ids):
        if i % 3 == 0:
            assert not w.is_alive(e)
        else:
            assert w.get(e, Health).hp == i


def test_destroy_rejects_duplicates_and_stale_without_change():
    w = World()
    ids = w.spawn_batch(5, Tag())
    with pytest.raises(ValueError, match="more than once"):
        w.destroy([ids[0], ids[0]])
    w.destroy(ids[1])
    with pytest.raises(DeadEntityError):
        w.destroy(ids[:3])  # ids[1] is dead: nothing destroyed
    assert len(w) == 4 and w.is_alive(ids[0]) and w.is_alive(ids[2])


def test_add_and_remove_move_rows_between_tables():
    w = World()
    ids = w.spawn_batch(10, Health(hp=np.arange(10, dtype=np.float32)))
    w.add(ids[2], Velocity(linear=(1, 2, 3)))
    assert w.has(ids[2], Velocity) and not w.has(ids[3], Velocity)
    assert w.get(ids[2], Health).hp == 2
    w.add(ids[4:8], Velocity(linear=np.ones((4, 3))))
    for i in range(10):
        assert w.get(ids[i], Health).hp == i
    w.remove(ids[5], Velocity)
    assert not w.has(ids[5], Velocity)
    assert w.get(ids[2], Velocity).linear.tolist() == [1, 2, 3]
    with pytest.raises(MissingComponentError, match="no Velocity"):
        w.remove(ids[0], Velocity)
    with pytest.raises(MissingComponentError):
        w.remove(ids[[2, 0]], Velocity)  # one lacks it: nothing removed
    assert w.has(ids[2], Velocity)


def test_add_existing_replaces_value():
    w = World()
    e = w.spawn(Health(hp=1))
    w.add(e, Health(hp=2))
    assert w.get(e, Health).hp == 2
    assert set(w.components(e)) == {Health}


def test_add_to_entities_in_different_tables_with_per_row_values():
    w = World()
    a = w.spawn_batch(3, Health())
    b = w.spawn_batch(3, Health(), Tag())
    ids = np.concatenate([a, b])
    lin = np.arange(18, dtype=np.float64).reshape(6, 3)
    w.add(ids[[0, 3, 1, 4]], Velocity(linear=lin[:4]))
    assert w.get(a[0], Velocity).linear.tolist() == lin[0].tolist()
    assert w.get(b[0], Velocity).linear.tolist() == lin[1].tolist()
    assert w.get(a[1], Velocity).linear.tolist() == lin[2].tolist()
    assert w.get(b[1], Velocity).linear.tolist() == lin[3].tolist()


def test_cannot_remove_a_required_component():
    w = World()
    e = w.spawn(Mesh())
    with pytest.raises(EcsError, match="Mesh requires it"):
        w.remove(e, ModelMatrix)


def test_set_whole_and_partial_and_many():
    w = World()
    ids = w.spawn_batch(4, Transform())
    w.set(ids[0], Transform(position=(1, 1, 1), scale=(2, 2, 2)))
    assert w.get(ids[0], Transform).scale.tolist() == [2, 2, 2]
    w.set(ids[1], Transform, position=(5, 0, 0))
    t = w.get(ids[1], Transform)
    assert t.position.tolist() == [5, 0, 0] and t.scale.tolist() == [1, 1, 1]
    w.set(ids[2:], Transform, position=np.array([[7, 0, 0], [8, 0, 0]]))
    assert w.get(ids[3], Transform).position[0] == 8
    with pytest.raises(MissingComponentError):
        w.set(ids[0], Health(hp=1))
    with pytest.raises(TypeError, match="no field"):
        w.set(ids[0], Transform, nope=1)


def test_quaternion_normalised_on_write_and_zero_rejected():
    w = World()
    e = w.spawn(Transform(rotation=(0, 0, 2, 0)))
    assert w.get(e, Transform).rotation.tolist() == [0, 0, 1, 0]
    with pytest.raises(ValueError, match="non-zero length"):
        w.set(e, Transform, rotation=(0, 0, 0, 0))
    assert w.get(e, Transform).rotation.tolist() == [0, 0, 1, 0]


@pytest.mark.parametrize(
    "value, field",
    [
        (Transform(position=(np.nan, 0, 0)), "Transform.position"),
        (Transform(scale=(1, np.inf, 1)), "Transform.scale"),
        (Transform(rotation=(0, 0, np.nan, 1)), "Transform.rotation"),
        (PointLight(intensity=np.nan), "PointLight.intensity"),
        (PointLight(color=(1, -np.inf, 0)), "PointLight.color"),
        (Camera(fov_y=np.nan), "Camera.fov_y"),
        (Camera(near=np.inf), "Camera.near"),
        (Camera(far=np.nan), "Camera.far"),
    ],
)
def test_nan_and_inf_rejected_naming_entity_and_field(value, field):
    w = World()
    e = w.spawn(type(value)())
    before = w.get(e, type(value))
    with pytest.raises(ValueError) as info:
        w.set(e, value)
    msg = str(info.value)
    assert field in msg and f"entity {e}" in msg
    assert w.get(e, type(value)) == before  # nothing lost
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        w.spawn(value)
    assert len(w) == 1


def test_camera_far_may_be_infinite():
    w = World()
    e = w.spawn(Camera(far=np.inf))
    assert w.get(e, Camera).far == np.inf


def test_batch_error_names_the_failing_row_and_spawns_nothing():
    w = World()
    pos = np.zeros((50, 3))
    pos[17, 1] = np.nan
    with pytest.raises(ValueError, match=r"row 17 of the batch.*Transform\.position"):
        w.spawn_batch(50, Transform(position=pos))
    assert len(w) == 0 and w.storage.index.used == 0


def test_batch_set_error_names_the_entity():
    w = World()
    ids = w.spawn_batch(5, Transform())
    pos = np.zeros((5, 3))
    pos[3, 0] = np.inf
    with pytest.raises(ValueError, match=f"entity {ids[3]} "):
        w.set(ids, Transform, position=pos)
    assert (w.query(Transform, write=()).column(Transform.position) == 0).all()


def test_wrong_shape_and_dtype_are_clear_errors():
    w = World()
    with pytest.raises(ValueError, match=r"Transform\.position expects \(3,\) per entity.*got shape \(2,\)"):
        w.spawn(Transform(position=(1, 2)))
    with pytest.raises(ValueError, match=r"Mesh\.handle holds uint32 values; got float64"):
        w.spawn(Mesh(handle=1.5))
    with pytest.raises(ValueError, match=r"Mesh\.handle must fit in uint32"):
        w.spawn(Mesh(handle=-1))
    with pytest.raises(ValueError, match=r"Transform\.position holds float64 values; got <U"):
        w.spawn(Transform(position=("a", "b", "c")))
    with pytest.raises(ValueError, match=r"shape \(4, 3\) for 4 entities; got shape \(3, 3\)"):
        w.spawn_batch(4, Transform(position=np.zeros((3, 3))))
    with pytest.raises(TypeError, match="not the class itself"):
        w.spawn(Transform)
    with pytest.raises(TypeError, match="has no field"):
        Transform(pos=(1, 2, 3))
    with pytest.raises(ValueError, match="given twice"):
        w.spawn(Health(), Health())
    assert len(w) == 0


def test_range_checks():
    w = World()
    with pytest.raises(ValueError, match=r"Health\.hp must be >= 0"):
        w.spawn(Health(hp=-1))
    with pytest.raises(ValueError, match=r"Camera\.near must be >= 1e-30"):
        w.spawn(Camera(near=0.0))
    with pytest.raises(ValueError, match=r"PointLight\.radius must be >= 0"):
        w.spawn(PointLight(radius=-2))


def test_plain_python_objects_as_components():
    class Position:
        def __init__(self, x):
            self.x = x

    w = World()
    p = Position(3)
    e = w.spawn(p, Health())
    assert w.get(e, Position) is p
    assert w.has(e, Position)
    for batch in w.query(Position, Health):
        col = batch[Position]
        assert col[0] is p
    w.remove(e, Position)
    assert not w.has(e, Position)
    with pytest.raises(TypeError, match="plain Python object"):
        w.spawn_batch(3, Position(1))


def test_user_component_with_shaped_fields():
    class Grid(Component):
        cells = Field(np.int16, (2, 2), default=((1, 2), (3, 4)))

    w = World()
    ids = w.spawn_batch(3, Grid())
    w.set(ids[1], Grid, cells=np.full((2, 2), 9))
    assert w.get(ids[0], Grid).cells.tolist() == [[1, 2], [3, 4]]
    assert w.get(ids[1], Grid).cells.tolist() == [[9, 9], [9, 9]]


def test_tables_grow_by_doubling_and_shrink():
    w = World()
    for _ in range(10):
        w.spawn_batch(100, Health())
    table = next(t for t in w.tables if t.has(Health))
    assert table.count == 1000
    assert table.capacity == 1600  # 100 -> 200 -> 400 -> 800 -> 1600
    w.shrink_to_fit()
    assert table.capacity == 1000
    assert w.memory_bytes() > 0


def test_memory_of_bulk_spawn_is_close_to_raw_columns():
    w = World()
    n = 100_000
    w.spawn_batch(n, Transform(), Velocity(), Mesh())
    raw = sum(
        t.count * col.dtype.itemsize * int(np.prod(col.shape[1:])) for t in w.tables for col in t.columns.values()
    )
    assert w.memory_bytes() / raw < 1.5


def test_cross_field_check_camera_near_below_far():
    w = World()
    with pytest.raises(ValueError, match=r"new entity: Camera\.near \(5\.0\) must be less than Camera\.far \(1\.0\)"):
        w.spawn(Camera(near=5.0, far=1.0))
    e = w.spawn(Camera(near=0.1, far=100.0))
    with pytest.raises(ValueError, match=f"entity {e} .*must be less than"):
        w.set(e, Camera, near=200.0)  # checked against the stored far
    assert w.get(e, Camera).near == 0.1
    w.set(e, Camera, far=np.inf)
    w.set(e, Camera, near=1000.0)
    assert w.get(e, Camera).near == 1000.0


def test_change_stamp_moves_with_writes_and_structure_only():
    w = World()
    a, b = w.spawn_batch(2, Transform(), Health())
    other = w.spawn(Transform())  # another table
    stamp = w.change_stamp(a, Transform)
    assert w.change_stamp(a, Transform) == stamp
    w.set(other, Transform, position=(1.0, 0.0, 0.0))
    w.set(a, Health, hp=5.0)
    assert w.change_stamp(a, Transform) == stamp  # other tables and components
    assert w.change_stamp(a, Transform, Health) != w.change_stamp(a, Transform)
    w.set(b, Transform, position=(2.0, 0.0, 0.0))
    moved = w.change_stamp(a, Transform)
    assert moved != stamp  # ticks are per table: a neighbour's write counts too
    for q in w.query(Transform, Health):
        q[Transform].scale[...] = 2.0  # a write through a query view
    assert w.change_stamp(a, Transform) != moved
    settled = w.change_stamp(a, Transform)
    w.destroy(b)  # structure: rows may move
    assert w.change_stamp(a, Transform) != settled
    with pytest.raises(MissingComponentError, match="Velocity"):
        w.change_stamp(a, Transform, Velocity)
    with pytest.raises(DeadEntityError):
        w.change_stamp(b, Transform)
