"""One-shot systems (ecs/one_shot.py): `run_once(world, f)` runs a system on request: at once
outside systems, at the requester's sync point inside one (after its structural changes, in
request order, the same in a parallel schedule), its declared access checked."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import AccessError, Component, EcsError, Field, Schedule, World, run_once, system
from ecs_engine.jobs import JobPool


class Enemy(Component):
    hp = Field(np.float32, default=3.0)


class Wave:
    def __init__(self) -> None:
        self.number = 0


@system(reads=[Wave], writes=[Enemy])
def spawn_wave(world, dt):
    wave = world.resources[Wave]
    wave.number += 1
    world.spawn_batch(wave.number, Enemy(hp=float(wave.number)))


def test_outside_systems_it_runs_now_and_its_changes_are_applied_when_it_returns():
    world = World()
    world.resources[Wave] = Wave()
    run_once(world, spawn_wave)
    assert world.query(Enemy).count() == 1  # applied already
    run_once(world, spawn_wave)
    assert world.query(Enemy).count() == 3 and world.resources[Wave].number == 2


def test_a_function_is_one_system_per_world_so_its_cursors_and_ticks_last():
    world, seen = World(), []
    world.spawn(Enemy())

    def changed_enemies(world, dt):
        seen.append(sum(len(b) for b in world.query(Enemy, write=()).iter(changed=(Enemy,))))

    run_once(world, changed_enemies)
    run_once(world, changed_enemies)  # nothing written since its last run
    world.set(world.query(Enemy).entities(), Enemy, hp=1.0)
    run_once(world, changed_enemies)
    assert seen == [1, 0, 1]


def test_requested_inside_systems_it_runs_at_their_sync_point_after_their_changes_in_request_order():
    world, log = World(), []
    world.resources[Wave] = Wave()

    def report(name):
        def run(world, dt):
            log.append((name, world.query(Enemy).count()))

        run.__name__ = name
        return run

    @system(writes=[Enemy])
    def first(world, dt):
        world.spawn(Enemy())  # applied before the one-shots run
        run_once(world, report("a"))
        run_once(world, spawn_wave)
        log.append("first")

    @system()
    def second(world, dt):
        run_once(world, report("b"))
        log.append("second")

    schedule = Schedule()
    schedule.add(first)
    schedule.add(second)
    schedule.add(report("late"), "post_update")
    schedule.run(world, 0.0)
    assert log == ["first", "second", ("a", 1), ("b", 2), ("late", 2)]


def test_inside_a_query_loop_outside_systems_it_waits_for_the_loop_s_end():
    world, log = World(), []
    world.spawn_batch(2, Enemy())
    for _batch in world.query(Enemy):
        run_once(world, lambda w, dt: log.append(w.query(Enemy).count()))
        world.spawn(Enemy())
        assert log == []
    assert log == [3]


def test_its_declared_access_is_checked():
    world = World()
    world.resources[Wave] = Wave()

    @system(reads=[Wave])
    def sneaky(world, dt):
        for batch in world.query(Enemy):
            batch[Enemy].hp[:] = 0

    world.spawn(Enemy())
    with pytest.raises(AccessError, match="sneaky queries \\['Enemy'\\] but does not declare them"):
        run_once(world, sneaky)


def test_bad_requests_are_one_clear_error():
    world = World()
    with pytest.raises(TypeError, match="run_once takes a system or a function of \\(world, dt\\), got int 5"):
        run_once(world, 5)
    with pytest.raises(ValueError, match="dt is a finite number of seconds, got nan"):
        run_once(world, spawn_wave, dt=float("nan"))
    with pytest.raises(ValueError, match="got True"):
        run_once(world, spawn_wave, dt=True)


def test_a_failing_one_shot_lets_the_others_run_and_is_raised_after():
    world, log = World(), []

    def broken(world, dt):
        raise RuntimeError("one-shot bug")

    @system()
    def requester(world, dt):
        run_once(world, broken)
        run_once(world, lambda w, dt: log.append("ran"))

    schedule = Schedule()
    schedule.add(requester)
    with pytest.raises(RuntimeError, match="one-shot bug"):
        schedule.run(world, 0.0)
    assert log == ["ran"]


def test_a_one_shot_that_requests_itself_forever_is_reported():
    world = World()

    def again(world, dt):
        run_once(world, again)

    with pytest.raises(EcsError, match=r"kept changing the world for 64 rounds.*again"):
        run_once(world, again)


def _waves(parallel: bool) -> tuple[list, list]:
    world = World()
    pool = world.resources[JobPool] = JobPool(4)
    world.resources[Wave] = Wave()
    order: list = []
    try:

        def requester(name):
            @system(reads=[Enemy], name=name)
            def run(world, dt):
                run_once(world, spawn_wave)
                run_once(world, lambda w, dt, name=name: order.append((name, w.query(Enemy).count())))

            return run

        schedule = Schedule(parallel=parallel)
        for name in ("a", "b", "c"):
            schedule.add(requester(name))  # read-only: they run together in parallel
        for _ in range(2):
            schedule.run(world, 0.0)
        return order, world.query(Enemy).column(Enemy.hp).tolist()
    finally:
        pool.close()


def test_a_parallel_schedule_runs_them_in_declared_order():
    sequential = _waves(parallel=False)
    assert [name for name, _ in sequential[0]] == ["a", "b", "c"] * 2
    assert _waves(parallel=True) == sequential
