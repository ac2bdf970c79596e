"""Queries, column views, deferred structural changes and change detection."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import AccessError, Component, EcsError, Field, World
from ecs_engine.components import Mesh, Transform, Velocity


class Health(Component):
    hp = Field(np.float32, default=100.0)


class Frozen(Component):
    pass


def make_world():
    w = World()
    a = w.spawn_batch(5, Transform(), Velocity(linear=(1, 0, 0)))
    b = w.spawn_batch(3, Transform(), Velocity(linear=(2, 0, 0)), Frozen())
    c = w.spawn_batch(4, Transform(), Health())
    return w, a, b, c


def test_query_matches_tables_with_filters():
    w, a, _b, _c = make_world()
    assert w.query(Transform).count() == 12
    assert w.query(Transform, Velocity).count() == 8
    assert w.query(Transform, without=[Frozen]).count() == 9
    assert w.query(Transform, with_=[Frozen]).count() == 3
    got = set(w.query(Velocity, without=[Frozen]).entities().tolist())
    assert got == set(a.tolist())


def test_query_is_cached_and_sees_new_tables():
    w, *_ = make_world()
    q = w.query(Transform, Velocity)
    assert w.query(Transform, Velocity) is q
    n_tables = len(q.tables)
    w.spawn(Transform(), Velocity(), Health())
    assert len(q.tables) == n_tables + 1
    assert q.count() == 9


def test_views_are_writable_column_slices_not_copies():
    w, a, _, _ = make_world()
    for batch in w.query(Transform, Velocity, without=[Frozen]):
        t = batch[Transform]
        assert t.position.base is not None  # a view
        t.position += batch[Velocity].linear
        batch[Transform.scale][:] = 2.0
    assert w.get(a[0], Transform).position.tolist() == [1, 0, 0]
    assert w.get(a[4], Transform).scale.tolist() == [2, 2, 2]
    assert len(batch) == 5 and batch.entities.tolist() == a.tolist()


def test_read_only_columns_reject_writes():
    w, *_ = make_world()
    for batch in w.query(Transform, Velocity, write=[Transform]):
        with pytest.raises(ValueError, match="read-only"):
            batch[Velocity].linear[0, 0] = 5
        with pytest.raises(ValueError, match="read-only"):
            batch.entities[0] = 1
        with pytest.raises(AccessError):
            batch[Health]


def test_write_must_be_queried():
    w, *_ = make_world()
    with pytest.raises(ValueError, match="must also be queried"):
        w.query(Transform, write=[Velocity])


def test_structural_changes_in_a_loop_are_deferred_then_applied():
    w, a, b, _c = make_world()
    spawned = []
    for batch in w.query(Transform, Velocity):
        for _ in batch.entities:
            spawned.append(w.spawn(Health(hp=1)))
        w.destroy(batch.entities[0])
        w.add(batch.entities[1], Health(hp=3))
        # nothing moved yet: the views stay valid
        assert w.query(Transform, Velocity).count() == 8
    assert len(spawned) == 8
    assert all(w.is_alive(e) for e in spawned)
    assert not w.is_alive(a[0]) and not w.is_alive(b[0])
    assert w.get(a[1], Health).hp == 3
    assert len(w) == 12 + 8 - 2


def test_reserved_entity_cannot_be_read_before_sync():
    w, *_ = make_world()
    with w.deferred():
        e = w.spawn(Health())
        with pytest.raises(Exception, match="next sync point"):
            w.get(e, Health)
        w.set(e, Health, hp=7)  # queued after the spawn
    assert w.get(e, Health).hp == 7


def test_deferred_destroy_twice_is_rejected_at_the_call():
    w, a, *_ = make_world()
    with w.deferred():
        w.destroy(a[0])
        with pytest.raises(EcsError, match="already queued"):
            w.destroy(a[0])
        with pytest.raises(EcsError, match="already queued"):
            w.add(a[0], Health())
    assert not w.is_alive(a[0])


def test_deferred_commands_apply_in_order():
    w, a, *_ = make_world()
    with w.deferred():
        w.add(a[0], Health(hp=1))
        w.set(a[0], Health, hp=2)
        w.remove(a[0], Velocity)
        w.remove(a[0], Velocity)  # already gone when applied: skipped
    assert w.get(a[0], Health).hp == 2
    assert not w.has(a[0], Velocity)


def test_flush_inside_a_loop_is_refused():
    w, *_ = make_world()
    for _ in w.query(Transform):
        with pytest.raises(EcsError, match="cannot run"):
            w.flush()
        break


def test_breaking_out_of_a_loop_ends_the_deferral():
    w, *_ = make_world()
    for _ in w.query(Transform):
        e = w.spawn(Health())
        break
    assert w.is_alive(e) and not w.deferring


def test_change_ticks_skip_unchanged_tables():
    w, a, _b, c = make_world()
    since = w.tick
    assert list(w.query(Transform).iter(changed=[Transform], since=since)) == []
    w.set(c[0], Health, hp=5)  # another component
    assert list(w.query(Transform, Health).iter(changed=[Transform], since=since)) == []
    w.set(a[0], Transform, position=(1, 2, 3))
    changed = list(w.query(Transform, write=()).iter(changed=[Transform], since=since))
    assert [len(x) for x in changed] == [5]
    # a writable query marks its columns changed
    since = w.tick
    for _ in w.query(Velocity, write=[Velocity]):
        pass
    assert len(list(w.query(Velocity, write=()).iter(changed=[Velocity], since=since))) == 2
    # new rows count as changed
    since = w.tick
    w.spawn(Transform(), Health())
    assert len(list(w.query(Transform, write=()).iter(changed=[Transform], since=since))) == 1


def test_changed_without_since_outside_a_system_is_an_error():
    w, *_ = make_world()
    with pytest.raises(EcsError, match="since="):
        list(w.query(Transform).iter(changed=[Transform]))


def test_query_column_concatenates_and_entities_match():
    w, _a, _b, _c = make_world()
    q = w.query(Transform, Velocity, write=())
    lin = q.column(Velocity.linear)
    assert lin.shape == (8, 3) and sorted(lin[:, 0].tolist()) == [1] * 5 + [2] * 3
    assert len(q.entities()) == 8


def test_empty_world_query():
    w = World()
    q = w.query(Mesh)
    assert q.count() == 0 and list(q) == [] and len(q.entities()) == 0
    assert q.column(Mesh.handle).shape == (0,)
