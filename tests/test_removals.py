"""Removal detection (ecs/removals.py): `world.removed(C).read()` gives the ids that lost C (or
were destroyed with it) since the reader last read, as an array, each reader on its own, like an
event channel; the same in a parallel schedule as in a sequential one."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import AccessError, Component, Field, Schedule, World, system
from ecs_engine.ecs.events import Reader
from ecs_engine.jobs import JobPool


class Health(Component):
    hp = Field(np.float32, default=10.0)


class Armor(Component):
    value = Field(np.float32, default=1.0)


def test_a_system_reads_each_removal_once_whether_removed_or_destroyed():
    world = World()
    world.removed(Health)  # recorded from here on
    a, b, c, d = world.spawn_batch(4, Health(), Armor())
    seen: list[list[int]] = []

    @system(reads=[Health])
    def forget(world, dt):
        seen.append(world.removed(Health).read().tolist())

    @system(writes=[Health])
    def hurt(world, dt):
        if len(seen) == 1:
            world.remove(a, Health)
            world.destroy(np.array([b, c]))

    schedule = Schedule()
    schedule.add(forget)  # before the remover: sees them the next frame
    schedule.add(hurt)
    for _ in range(3):
        schedule.run(world, 0.0)
    assert seen == [[], [a, b, c], []]
    world.destroy(d)  # outside systems, at once
    schedule.run(world, 0.0)
    assert seen[-1] == [d]
    assert world.removed(Health).read().dtype == np.int64


def test_readers_are_independent_and_one_two_frames_behind_loses_the_oldest():
    world = World()
    channel = world.removed(Armor)
    early, late = Reader(), Reader()
    ids = world.spawn_batch(3, Armor())
    world.remove(ids[0], Armor)
    assert channel.read(early).tolist() == [ids[0]]
    world.update_events()  # a frame boundary
    world.remove(ids[1], Armor)
    assert channel.read(early).tolist() == [ids[1]]
    world.update_events()
    world.update_events()
    world.destroy(ids[2])
    assert channel.read(late).tolist() == [ids[2]]  # ids[0] and ids[1] went two frames ago
    assert channel.dropped == 2


def test_removals_before_anything_asked_are_not_recorded_and_unwatched_worlds_record_nothing():
    world = World()
    first = world.spawn(Health())
    world.remove(first, Health)
    assert world.storage.log is None  # nobody watches: nothing recorded, nothing paid
    second = world.spawn(Health())
    channel = world.removed(Health)
    world.destroy(second)
    assert channel.read().tolist() == [second]


def test_reading_removals_needs_the_component_declared():
    world = World()

    @system(reads=[Armor])
    def sneaky(world, dt):
        world.removed(Health).read()

    schedule = Schedule()
    schedule.add(sneaky)
    with pytest.raises(AccessError, match="sneaky reads Health removals but does not declare them in reads"):
        schedule.run(world, 0.0)
    with pytest.raises(TypeError, match="expected a component type"):
        world.removed(5)


def _removed_by_frame(parallel: bool) -> list[list[int]]:
    world = World()
    pool = world.resources[JobPool] = JobPool(4)
    try:
        world.removed(Health)
        world.spawn_batch(30, Health(hp=np.arange(30, dtype=np.float32)), Armor())
        seen: list[list[int]] = []

        @system(reads=[Health])
        def reader(world, dt):
            seen.append(world.removed(Health).read().tolist())

        @system(writes=[Health])
        def low(world, dt):
            for batch in world.query(Health):
                world.remove(batch.entities[batch[Health].hp < 3], Health)
                batch[Health].hp -= 1

        @system(writes=[Armor])
        def breaker(world, dt):
            for batch in world.query(Armor):
                world.destroy(batch.entities[-2:])

        schedule = Schedule(parallel=parallel)
        for s in (reader, low, breaker):
            schedule.add(s)
        for _ in range(5):
            schedule.run(world, 0.0)
        return seen
    finally:
        pool.close()


def test_a_parallel_schedule_sees_the_removals_a_sequential_one_does():
    sequential = _removed_by_frame(parallel=False)
    assert sum(map(len, sequential)) > 10
    assert _removed_by_frame(parallel=True) == sequential
