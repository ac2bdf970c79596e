"""Observers (ecs/observers.py, reactions.py): a function run with the batch of entities that
gained, lost or changed a component, at the sync point where the change is applied, in bulk,
in a defined order, the same in a parallel schedule as in a sequential one."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import (
    AccessError,
    Component,
    EcsError,
    Field,
    OnAdd,
    OnChange,
    OnRemove,
    Schedule,
    World,
    system,
)
from ecs_engine.ecs.observers import MAX_ROUNDS
from ecs_engine.jobs import JobPool


class Health(Component):
    hp = Field(np.float32, default=10.0)


class Armor(Component):
    value = Field(np.float32, default=1.0)


class Bar(Component):
    width = Field(np.float32, default=0.0)


def recorder(log: list, tag: str):
    def observe(world, trigger):
        log.append((tag, trigger.kind, trigger.entities.tolist()))

    observe.__name__ = tag
    return observe


def test_on_add_gets_a_whole_spawn_in_one_call_at_once_outside_systems():
    world, log = World(), []
    world.add_observer(OnAdd(Health), recorder(log, "added"))
    ids = world.spawn_batch(1000, Health(hp=np.arange(1000, dtype=np.float32)))
    assert log == [("added", "add", ids.tolist())]  # one call, every id, right after the spawn
    other = world.spawn(Armor())
    world.add(other, Health())  # gaining it later counts too
    assert log[-1] == ("added", "add", [other])
    world.spawn(Armor())  # not watched: no call
    assert len(log) == 2


def test_observers_run_at_the_stage_sync_point_in_the_order_added_with_everything_in_request_order():
    world, log = World(), []
    world.add_observer(OnAdd(Health), recorder(log, "first"))
    world.add_observer(OnAdd(Health), recorder(log, "second"))
    spawned: list = []

    def spawner(count):
        @system(writes=[Health], name=f"spawn{count}")
        def spawn(world, dt):
            spawned.append(world.spawn_batch(count, Health()).tolist())
            log.append(("system", count))

        return spawn

    schedule = Schedule()
    schedule.add(spawner(2))
    schedule.add(spawner(3))
    schedule.run(world, 0.0)
    both = spawned[0] + spawned[1]
    assert log == [("system", 2), ("system", 3), ("first", "add", both), ("second", "add", both)]


def test_on_remove_gets_the_values_as_they_were_for_removals_and_destructions():
    world, seen = World(), []
    world.add_observer(OnRemove(Health), lambda w, t: seen.append((t.entities.tolist(), t.values.hp.tolist())))
    a, b, c = world.spawn_batch(3, Health(hp=[1.0, 2.0, 3.0]), Armor())
    world.remove(a, Health)
    world.destroy(np.array([b, c]))
    assert seen == [([a], [1.0]), ([b, c], [2.0, 3.0])]
    world.destroy(a)  # no Health any more: nothing
    assert len(seen) == 2
    with pytest.raises(AccessError, match="read-only"):  # the values are a copy, read-only
        world.add_observer(OnRemove(Armor), lambda w, t: t.values.value.__setitem__(0, 5.0))
        world.destroy(world.spawn(Armor()))


def test_gained_and_lost_in_one_sync_point_shows_only_as_a_removal():
    world, log = World(), []
    world.add_observer(OnAdd(Health), recorder(log, "add"))
    world.add_observer(OnRemove(Health), recorder(log, "remove"))
    keep = world.spawn(Armor())
    with world.deferred():
        gone = world.spawn(Health())
        world.destroy(gone)
        world.add(keep, Health())
    assert log == [("add", "add", [keep]), ("remove", "remove", [gone])]


def test_on_change_reports_whole_tables_written_since_the_observer_last_ran():
    world, log = World(), []
    plain = world.spawn_batch(3, Health())
    armored = world.spawn_batch(2, Health(), Armor())
    world.add_observer(OnChange(Health), recorder(log, "changed"))
    schedule = Schedule()
    hurt = system(writes=[Health], reads=[Armor])(
        lambda world, dt: [b[Health].hp.__isub__(1) for b in world.query(Health, with_=[Armor])]
    )
    schedule.add(hurt)
    schedule.run(world, 0.0)
    assert log == [("changed", "change", armored.tolist())]  # only the table written
    world.set(plain[0], Health, hp=5.0)  # one row of a table: the whole table (ticks per table)
    schedule.stages["update"].clear()
    schedule._queues["update"].clear()
    schedule.run(world, 0.0)
    assert log[-1] == ("changed", "change", plain.tolist())
    schedule.run(world, 0.0)  # nothing written since: no call
    assert len(log) == 2


def test_an_observer_s_changes_apply_at_once_and_set_off_the_next_observers():
    world, log = World(), []

    def give_bars(world, trigger):
        world.add(trigger.entities, Bar(width=1.0))  # deferred: applied right after the observers

    world.add_observer(OnAdd(Health), give_bars)
    world.add_observer(OnAdd(Bar), recorder(log, "bars"))
    ids = world.spawn_batch(4, Health())
    assert log == [("bars", "add", ids.tolist())]
    assert world.query(Bar).count() == 4


def test_observers_that_feed_each_other_forever_are_reported():
    world = World()
    world.add_observer(OnAdd(Health), lambda w, t: (w.remove(t.entities, Health), w.add(t.entities, Armor())))
    world.add_observer(OnAdd(Armor), lambda w, t: (w.remove(t.entities, Armor), w.add(t.entities, Health())))
    with pytest.raises(EcsError, match=f"for {MAX_ROUNDS} rounds.*<lambda>"):
        world.spawn(Health())


def test_bad_input_is_one_clear_error():
    world = World()
    with pytest.raises(TypeError, match="OnAdd takes a component type"):
        OnAdd(Health())
    with pytest.raises(TypeError, match="OnAdd\\(C\\), OnRemove\\(C\\) or OnChange\\(C\\)"):
        world.add_observer(Health, print)
    with pytest.raises(TypeError, match="function of \\(world, trigger\\)"):
        world.add_observer(OnAdd(Health), 5)
    observer = world.add_observer(OnAdd(Health), print)
    world.remove_observer(observer)
    with pytest.raises(ValueError, match="not an observer of this world"):
        world.remove_observer(observer)
    assert world.storage.log is None  # nothing watched: nothing recorded


def test_an_observer_s_declared_access_is_checked():
    world = World()
    world.add_observer(OnAdd(Health), lambda w, t: w.query(Armor).count() and list(w.query(Armor)), reads=[Health])
    with pytest.raises(AccessError, match="queries \\['Armor'\\] but does not declare"):
        world.spawn(Health(), Armor())


def test_a_failing_observer_lets_the_others_run_and_is_raised_after():
    world, log = World(), []

    def broken(world, trigger):
        raise RuntimeError("observer bug")

    world.add_observer(OnAdd(Health), broken)
    world.add_observer(OnAdd(Health), recorder(log, "after"))
    with pytest.raises(RuntimeError, match="observer bug"):
        world.spawn(Health())
    assert len(log) == 1 and len(world) == 1


def test_a_scene_load_is_observed_once_with_entity_fields_remapped(tmp_path):
    from ecs_engine.components.hierarchy import Parent

    source = World()
    root = source.spawn(Health())
    source.spawn(Health(), Parent(entity=root))
    path = tmp_path / "two.scene"
    source.save(path, resources=())
    world, seen = World(), []
    world.add_observer(OnAdd(Parent), lambda w, t: seen.append([w.get(e, Parent).entity for e in t.entities]))
    world.add_observer(OnAdd(Health), lambda w, t: seen.append(len(t)))
    World.load(path, into=world, resources=())
    assert seen[0] == [world.query(Health, without=[Parent]).entities()[0]]  # the new root, not -1
    assert seen[1] == 2
    broken = tmp_path / "broken.scene"
    broken.write_bytes(path.read_bytes()[:-40])
    with pytest.raises(ValueError):
        World.load(broken, into=world, resources=())
    assert len(seen) == 2  # a load that fails reports nothing


def _run_game(parallel: bool) -> tuple[list, list]:
    """Systems of one stage that spawn, add, remove and destroy, observed; the calls and ids."""
    world, log = World(), []
    pool = world.resources[JobPool] = JobPool(4)
    try:
        world.add_observer(OnAdd(Health), recorder(log, "add health"))
        world.add_observer(OnRemove(Health), lambda w, t: log.append(("rm", t.entities.tolist(), t.values.hp.tolist())))
        world.add_observer(OnAdd(Armor), recorder(log, "add armor"))
        world.add_observer(OnChange(Bar), recorder(log, "bar changed"))
        world.spawn_batch(20, Health(hp=np.arange(20, dtype=np.float32)))
        world.spawn_batch(5, Bar())
        schedule = Schedule(parallel=parallel)

        @system(writes=[Health])
        def spawner(world, dt):
            world.spawn_batch(3, Health(hp=7.0))

        @system(reads=[Health], writes=[Armor])
        def armorer(world, dt):
            world.add(world.query(Health, without=[Armor]).entities()[:4], Armor())

        @system(writes=[Bar])
        def bars(world, dt):
            for batch in world.query(Bar):
                batch[Bar].width += 1.0
            world.spawn(Bar(), Health())

        @system(reads=[Armor], writes=[Health])
        def killer(world, dt):
            for batch in world.query(Health, with_=[Armor]):
                world.destroy(batch.entities[:1])

        for s in (spawner, armorer, bars, killer):
            schedule.add(s)
        for _ in range(3):
            schedule.run(world, 1 / 60)
        return log, world.entities().tolist()
    finally:
        pool.close()


def test_a_parallel_schedule_reports_what_a_sequential_one_does():
    assert _run_game(parallel=True) == _run_game(parallel=False)
