"""The parallel schedule (ecs/schedule.py): systems whose declared access does not conflict run
at the same time on the JobPool, conflicting ones never overlap and keep their declared order,
structural changes apply in declared order, errors surface as raised, and the result equals the
sequential schedule's."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from ecs_engine import AccessError, Schedule, World, system
from ecs_engine.components import AngularVelocity, Transform, Velocity
from ecs_engine.ecs import Component, Field
from ecs_engine.ecs.schedule import conflict, levels
from ecs_engine.jobs import JobPool


class A(Component):
    x = Field(np.float64)


class B(Component):
    x = Field(np.float64)


class C(Component):
    x = Field(np.float64)


class Score:
    """A resource type, declared like a component."""


def named(name: str, reads=(), writes=()):
    return system(reads=reads, writes=writes, name=name)(lambda world, dt: None)


def test_levels_keep_conflicting_systems_in_order_and_group_the_rest():
    a = named("a", writes=[A])
    b = named("b", writes=[B])
    c = named("c", reads=[A], writes=[C])  # after a
    d = named("d", reads=[B])  # after b
    e = named("e", reads=[Score])
    f = named("f", writes=[Score])  # after e (it reads what f writes)
    g = system(reads=None, writes=None, name="g")(lambda world, dt: None)  # undeclared: alone, after all
    systems = [a, b, c, d, e, f, g]
    assert [[systems[i].name for i in group] for group in levels(systems)] == [
        ["a", "b", "e"],
        ["c", "d", "f"],
        ["g"],
    ]
    assert not conflict(a, b) and conflict(a, c) and conflict(c, a) and not conflict(c, d)
    assert conflict(named("r1", reads=[A]), named("w1", writes=[A]))
    assert not conflict(named("r1", reads=[A]), named("r2", reads=[A]))
    exclusive = named("x", reads=[C])
    exclusive.exclusive = True
    assert conflict(exclusive, named("y", reads=[Score]))


def world_with_pool(threads: int) -> tuple[World, JobPool]:
    world = World()
    pool = JobPool(threads)
    world.resources[JobPool] = pool
    return world, pool


def test_independent_systems_overlap_and_conflicting_ones_never_do():
    """Two independent systems meet at a barrier (it would time out if they ran one after the
    other); two that write the same component never run at once."""
    world, pool = world_with_pool(4)
    barrier = threading.Barrier(2, timeout=10)
    active, most = [0], [0]
    lock = threading.Lock()

    def tracked(name: str, writes):
        def run(world, dt):
            with lock:
                active[0] += 1
                most[0] = max(most[0], active[0])
            threading.Event().wait(0.02)
            with lock:
                active[0] -= 1

        return system(writes=writes, name=name)(run)

    try:
        meet = Schedule(("update",), parallel=True)
        meet.add(system(writes=[A], name="left")(lambda world, dt: barrier.wait()))
        meet.add(system(writes=[B], name="right")(lambda world, dt: barrier.wait()))
        meet.run(world, 0.0)  # a BrokenBarrierError here: they did not run together

        apart = Schedule(("update",), parallel=True)
        for i in range(4):
            apart.add(tracked(f"writer{i}", [A]))
        apart.run(world, 0.0)
        assert most[0] == 1
        assert apart.groups("update") == [["writer0"], ["writer1"], ["writer2"], ["writer3"]]
    finally:
        pool.close()


def run_game(parallel: bool, threads: int) -> tuple[World, list[str]]:
    """Independent systems that each spawn, write their own column and log; a reader after them."""
    world, pool = world_with_pool(threads)
    world.spawn_batch(100, A(x=np.arange(100.0)), B(x=1.0), C(x=2.0))
    log: list[str] = []

    def writer(kind):
        @system(writes=[kind], name=f"write_{kind.__name__}")
        def run(world, dt):
            for batch in world.query(kind):
                batch[kind].x += 1.0
            world.spawn(kind(x=-1.0))  # deferred: applied in declared order at the sync point

        return run

    @system(reads=[A, B, C], name="reader")
    def reader(world, dt):
        log.append(f"{world.query(A).count()} {world.query(B).count()} {world.query(C).count()}")

    schedule = Schedule(("update",), parallel=parallel)
    for kind in (A, B, C):
        schedule.add(writer(kind))
    schedule.add(reader)
    try:
        for _ in range(3):
            schedule.run(world, 0.0)
    finally:
        pool.close()
    return world, log


def table_state(world: World) -> list[tuple]:
    return [
        (tuple(sorted(t.__name__ for t in table.types)), table.count, table.entities[: table.count].tolist())
        + tuple(table.columns[(ct, "x")][: table.count].tolist() for ct in (A, B, C) if table.has(ct))
        for table in world.tables
    ]


def test_a_parallel_schedule_gives_the_sequential_result():
    sequential, log_a = run_game(False, 1)
    parallel, log_b = run_game(True, 4)
    assert log_a == log_b == ["100 100 100", "101 101 101", "102 102 102"]
    # spawns from systems that ran together are applied in declared order: the same rows; the
    # ids match too here because each system spawned once (allocation order is the lock's)
    assert sorted(map(str, table_state(sequential))) == sorted(map(str, table_state(parallel)))


def test_errors_and_access_checks_surface_from_parallel_systems():
    world, pool = world_with_pool(4)
    world.spawn(Transform(), Velocity(), AngularVelocity())
    try:

        @system(reads=[Velocity], name="sneaky")
        def sneaky(world, dt):
            world.query(Transform)  # undeclared

        @system(writes=[A], name="fails")
        def fails(world, dt):
            raise RuntimeError("boom in fails")

        schedule = Schedule(("update",), parallel=True)
        schedule.add(sneaky)
        schedule.add(named("other", writes=[B]))
        with pytest.raises(AccessError, match="sneaky"):
            schedule.run(world, 0.0)
        schedule = Schedule(("update",), parallel=True)
        schedule.add(fails)
        schedule.add(named("other", writes=[B]))
        with pytest.raises(RuntimeError, match="boom in fails"):
            schedule.run(world, 0.0)
        assert not world.deferring  # the failed frame left no system running on this thread
    finally:
        pool.close()


def test_each_system_keeps_its_own_change_ticks():
    world, pool = world_with_pool(4)
    world.spawn(A(), B())
    seen: dict[str, int] = {}

    def changed_reader(kind, name):
        @system(reads=[kind], name=name)
        def run(world, dt):
            seen[name] = sum(len(b) for b in world.query(kind).iter(changed=(kind,)))

        return run

    try:
        schedule = Schedule(("update",), parallel=True)
        schedule.add(changed_reader(A, "sees_a"))
        schedule.add(changed_reader(B, "sees_b"))
        schedule.run(world, 0.0)
        assert seen == {"sees_a": 1, "sees_b": 1}  # spawned before their first run
        world.set(world.query(A).entities(), A(x=3.0))
        schedule.run(world, 0.0)
        assert seen == {"sees_a": 1, "sees_b": 0}  # only A was written since each one's last run
        ticks = [s.last_run_tick for s in schedule.stages["update"]]
        assert ticks[0] < ticks[1]  # handed out in declared order
    finally:
        pool.close()
