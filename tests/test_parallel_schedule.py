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
    # spawns from systems that ran together are applied in declared order: the same rows, and
    # the same ids (each system takes those of its place in the stage, see stage_ids.py)
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


# ------------------------------------------------------------------ determinism (issue 34, #10)
class D(Component):
    x = Field(np.float64, (2,))


KINDS = (A, B, C, D)


def spawner(kind, times: int, name: str):
    @system(writes=[kind], name=name)
    def run(world, dt):
        for _ in range(times):
            world.spawn_batch(2, kind(x=1.0))

    return run


def id_layout(parallel: bool, pool: JobPool | None) -> tuple:
    world = World()
    if pool is not None:
        world.resources[JobPool] = pool
    schedule = Schedule(("update",), parallel=parallel)
    schedule.add(spawner(A, 200, "spawn_a"))
    schedule.add(spawner(B, 200, "spawn_b"))
    schedule.run(world, 0.0)
    return tuple(tuple(world.query(kind).entities().tolist()) for kind in (A, B))


def test_systems_spawning_together_get_the_ids_they_get_in_sequence():
    """Two systems with disjoint writes, each calling spawn_batch 200 times in one stage: their
    ids interleaved as the threads happened to take them (7 layouts in 40 runs)."""
    pool = JobPool(2)
    try:
        layouts = {id_layout(True, pool) for _ in range(40)}
    finally:
        pool.close()
    assert layouts == {id_layout(False, None)}


class RandomSystem:
    """A system drawn from a seed: random declared reads and writes, and each run a random mix
    of spawns, destroys, adds, removes, sets, writes through views and reads (get and queries)
    that respects them. Its draws depend only on the seed and its run count, so a sequential
    and a parallel schedule built from the same seeds make the same requests."""

    def __init__(self, seed: int, name: str) -> None:
        rng = np.random.default_rng(seed)
        self.seed, self.runs = seed, 0
        self.reads = [k for k in KINDS if rng.random() < 0.2]
        self.writes = [k for k in KINDS if rng.random() < 0.2]
        self.system = system(reads=self.reads, writes=self.writes, name=name)(self.run)

    def run(self, world: World, dt: float) -> None:
        rng = np.random.default_rng([self.seed, self.runs])
        self.runs += 1
        everyone = world.entities()
        gone: set[int] = set()  # destroyed by this run: no later request may name them

        def pick(ids: np.ndarray, most: int) -> np.ndarray:
            ids = np.array([e for e in ids.tolist() if e not in gone], dtype=np.int64)
            return rng.choice(ids, size=min(len(ids), int(rng.integers(0, most + 1))), replace=False)

        def values(kind, n: int):
            return kind(x=rng.normal(size=(n, 2) if kind is D else n))

        for op in rng.choice(["spawn", "destroy", "add", "remove", "set", "write", "read"], size=6):
            if op == "spawn":
                kinds = [k for k in KINDS if rng.random() < 0.5]
                n = int(rng.integers(0, 40))
                if rng.random() < 0.5:
                    world.spawn(*(values(k, 1) for k in kinds))
                else:
                    world.spawn_batch(n, *(values(k, n) for k in kinds))
            elif op == "destroy":
                chosen = pick(everyone, 5)
                world.destroy(chosen)
                gone.update(chosen.tolist())
            elif op == "add":
                kind = KINDS[rng.integers(len(KINDS))]
                chosen = pick(everyone, 6)
                world.add(chosen, values(kind, len(chosen)))
            elif op == "remove":
                kind = KINDS[rng.integers(len(KINDS))]
                world.remove(pick(np.array([e for e in everyone.tolist() if world.has(e, kind)]), 4), kind)
            elif op == "set" and self.writes:
                kind = self.writes[rng.integers(len(self.writes))]
                chosen = pick(world.query(kind).entities(), 6)
                world.set(chosen, values(kind, len(chosen)))
            elif op == "write" and self.writes:
                kind = self.writes[rng.integers(len(self.writes))]
                for batch in world.query(kind):
                    batch[kind].x *= rng.uniform(0.5, 1.5)
            elif op == "read" and self.reads and self.writes:
                source, target = self.reads[rng.integers(len(self.reads))], self.writes[0]
                total = float(np.sum(world.query(source, write=()).column(source.x)))
                some = world.query(source, write=()).entities()
                if len(some):
                    total += float(np.sum(world.get(int(some[0]), source).x))
                for batch in world.query(target):
                    batch[target].x += total * 1e-3


def state(world: World) -> list[tuple]:
    """Every table's components, entity ids (in row order) and columns."""
    return sorted(
        (
            tuple(sorted(t.__name__ for t in table.types)),
            table.entities[: table.count].tolist(),
            [table.columns[(ct, "x")][: table.count].tolist() for ct in KINDS if table.has(ct)],
        )
        for table in world.tables
        if table.count
    )


def random_run(seed: int, parallel: bool, pool: JobPool | None, frames: int = 3) -> list:
    rng = np.random.default_rng(seed)
    world = World()
    if pool is not None:
        world.resources[JobPool] = pool
    world.spawn_batch(30, A(x=rng.normal(size=30)), B(x=1.0))
    world.spawn_batch(20, C(x=rng.normal(size=20)), D(x=(1.0, 2.0)))
    world.spawn_batch(10, A(), C(), D())
    schedule = Schedule(("update", "post_update"), parallel=parallel)
    for i in range(int(rng.integers(2, 7))):
        schedule.add(RandomSystem(seed * 100 + i, f"s{i}").system, "update" if rng.random() < 0.7 else "post_update")
    seen = []
    for _ in range(frames):
        try:
            schedule.run(world, 0.0)
            seen.append(state(world))
        except Exception as exc:  # the same failure in both is still the same result
            seen.append(f"{type(exc).__name__}: {exc}")
    return seen


def check_random_schedules(seeds: range) -> None:
    pool = JobPool(3)
    try:
        for seed in seeds:
            assert random_run(seed, True, pool) == random_run(seed, False, None), f"seed {seed}"
    finally:
        pool.close()


def test_random_parallel_schedules_give_the_sequential_ids_and_columns():
    check_random_schedules(range(60))


@pytest.mark.slow
def test_300_random_parallel_schedules_give_the_sequential_ids_and_columns():
    check_random_schedules(range(300))


def test_a_system_that_lies_about_its_access_is_caught_for_get_locate_and_change_stamp():
    """A query or a set of an undeclared component raised already; world.get read a torn value
    while another system wrote it, and world.locate handed out a table to write anything."""
    world = World()
    e = world.spawn(A(x=1.0), B(), C())
    calls = {
        "get": lambda: world.get(e, C),
        "change_stamp": lambda: world.change_stamp(e, A, C),
        "locate": lambda: world.locate(e),
    }
    for call, fn in calls.items():

        @system(reads=[A], writes=[B], name="liar")
        def liar(world, dt, fn=fn):
            assert world.get(e, A).x == 1.0 and world.get(e, B).x == 0.0  # declared: fine
            fn()

        with pytest.raises(AccessError, match=rf"system liar .*{call}"):
            world.run_system(liar, 0.0)
    seen = []
    anything = system(reads=None, writes=None, name="anything")(lambda world, dt: seen.append(world.locate(e)[1]))
    world.run_system(anything, 0.0)  # undeclared: it runs alone, so it may
    assert seen == [0] and world.get(e, C).x == 0.0  # and outside systems too


@pytest.mark.parametrize("parallel", [False, True])
def test_requests_naming_an_entity_an_earlier_system_destroyed_are_left_out(parallel):
    """Each system queues on its own: one that adds to, sets, removes from or destroys an entity
    that a system declared before it destroyed in the same stage changes nothing there."""
    world, pool = world_with_pool(2)
    doomed = world.spawn(A(x=1.0), B(x=1.0))
    kept = world.spawn(A(x=2.0), B(x=2.0))
    schedule = Schedule(("update",), parallel=parallel)
    schedule.add(system(name="killer")(lambda world, dt: world.destroy(doomed)))

    @system(writes=[B], name="late")
    def late(world, dt):
        both = np.array([doomed, kept])
        world.add(both, C(x=np.array([5.0, 6.0])))
        world.remove(both, A)
        world.set(both, B, x=np.array([7.0, 8.0]))  # queued behind the add on the same entities
        world.destroy(doomed)

    schedule.add(late)
    try:
        schedule.run(world, 0.0)
    finally:
        pool.close()
    assert not world.is_alive(doomed) and world.components(kept) == (B, C)
    assert world.get(kept, B).x == 8.0 and world.get(kept, C).x == 6.0


def test_a_stage_reuses_free_slots_and_gives_back_the_ones_no_system_took():
    world = World()
    first = world.spawn_batch(10, A())
    world.destroy(first[:6])
    free_before = world.storage.index.free_in_pop_order().tolist()
    taken: dict[str, list[int]] = {}

    def spawning(name, n):
        return system(name=name)(lambda world, dt: taken.setdefault(name, world.spawn_batch(n, B()).tolist()))

    alone = Schedule(("update",))
    alone.add(spawning("alone", 4))
    alone.run(world, 0.0)  # a stage of one system takes the ids spawn_batch would outside one
    assert [e & 0xFFFFFFFF for e in taken["alone"]] == free_before[:4]
    used = world.storage.index.used
    three = Schedule(("update",))
    for name, n in (("s0", 1), ("s1", 0), ("s2", 3)):
        three.add(spawning(name, n))
    three.run(world, 0.0)
    slots = {name: [e & 0xFFFFFFFF for e in ids] for name, ids in taken.items()}
    assert slots["s0"] == free_before[4:5]  # the free list first, in allocate's order
    # s2's first block starts 2 blocks of 64 into the stage's slots: the 2 free ones, then fresh
    assert slots["s2"] == [used + 128 - 2 + k for k in range(3)]
    index = world.storage.index
    assert index.used == used + 128 + 1
    # what no system took is free again: the free slot s0 left, then the fresh slots skipped
    assert index.free_in_pop_order().tolist() == free_before[5:] + list(range(used, used + 126))
    assert len(world) == 4 + 4 + 1 + 3 and not world.alive(np.arange(used, used + 126) + (1 << 32)).any()
    world.spawn_batch(3, C())  # outside the stage: from the free list again
    assert [e & 0xFFFFFFFF for e in world.query(C).entities()] == [free_before[5], used, used + 1]
