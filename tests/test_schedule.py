"""Systems, declared access, the schedule's order and its sync points."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import AccessError, EcsError, Schedule, System, World, system
from ecs_engine.components import (
    AngularVelocity,
    Mesh,
    ModelMatrix,
    RenderOrigin,
    Transform,
    Velocity,
)
from ecs_engine.systems import MotionSystem, TransformSystem


def test_systems_run_in_stated_order_with_sync_points():
    w = World()
    log = []

    @system(reads=[Velocity])
    def spawner(world, dt):
        log.append(("spawner", world.query(Velocity).count()))
        world.spawn(Velocity())  # deferred to the end of the stage

    @system(reads=[Velocity])
    def counter(world, dt):
        log.append(("counter", world.query(Velocity).count()))

    @system(reads=[Velocity])
    def later(world, dt):
        log.append(("later", world.query(Velocity).count()))

    s = Schedule()
    s.add(spawner)
    s.add(counter)
    s.add(later, "post_update")
    s.run(w, 0.1)
    assert log == [("spawner", 0), ("counter", 0), ("later", 1)]
    assert s.order() == [("update", ["spawner", "counter"]), ("post_update", ["later"])]


def test_declared_access_is_enforced():
    w = World()
    w.spawn(Transform(), Velocity())

    @system(reads=[Velocity], writes=[Transform])
    def good(world, dt):
        for b in world.query(Transform, Velocity):
            b[Transform].position += b[Velocity].linear
            with pytest.raises(ValueError, match="read-only"):
                b[Velocity].linear[:] = 0

    @system(reads=[Transform])
    def sneaky(world, dt):
        world.query(Transform, Velocity)

    @system(reads=[Transform])
    def writer(world, dt):
        world.query(Transform, write=[Transform])

    @system(reads=[Transform])
    def setter(world, dt):
        world.set(world.query(Transform).entities()[0], Transform, position=(1, 1, 1))

    s = Schedule()
    s.add(good)
    s.run(w, 1.0)
    for bad, pattern in [(sneaky, "does not declare"), (writer, "read-only"), (setter, "does not declare")]:
        s2 = Schedule()
        s2.add(bad)
        with pytest.raises(AccessError, match=pattern):
            s2.run(w, 1.0)


def test_changed_filter_uses_last_run_tick_and_excludes_own_writes():
    w = World()
    e = w.spawn(Transform(), Velocity())
    seen = []

    @system(reads=[Transform])
    def watcher(world, dt):
        seen.append(sum(len(b) for b in world.query(Transform).iter(changed=[Transform])))

    s = Schedule()
    s.add(watcher)
    s.run(w, 0.0)  # first run: everything is new
    s.run(w, 0.0)  # nothing changed
    w.set(e, Transform, position=(1, 0, 0))
    s.run(w, 0.0)
    s.run(w, 0.0)
    assert seen == [1, 0, 1, 0]


@pytest.mark.parametrize("parallel", [False, True])
def test_a_run_condition_skips_a_system_and_keeps_its_change_tick(parallel):
    """run_if=any_with(Velocity): not called while no entity has a Velocity; once one has, its
    `changed` filter sees every change since its last run, made while it was skipped too. A
    parallel schedule asks the condition as well."""
    from ecs_engine import any_with
    from ecs_engine.jobs import JobPool

    w = World()
    if parallel:
        w.resources[JobPool] = JobPool(2)
    e = w.spawn(Transform())
    seen = []

    @system(reads=[Transform, Velocity], run_if=any_with(Transform, Velocity))
    def mover(world, dt):
        seen.append(sum(len(b) for b in world.query(Transform, Velocity).iter(changed=[Transform])))

    @system(reads=[Transform])
    def other(world, dt):  # a second system, so the parallel schedule has a stage to spread
        pass

    s = Schedule(parallel=parallel)
    s.add(mover)
    s.add(other)
    s.run(w, 0.0)
    assert seen == []  # no Velocity anywhere: skipped
    w.add(e, Velocity())
    s.run(w, 0.0)  # first run: everything is new
    s.run(w, 0.0)  # nothing changed
    last = mover.last_run_tick
    w.remove(e, Velocity)
    s.run(w, 0.0)
    assert mover.last_run_tick == last  # skipped: the tick stays
    w.set(e, Transform, position=(1, 0, 0))  # a change while skipped
    w.add(e, Velocity())
    s.run(w, 0.0)
    assert seen == [1, 0, 1]
    if parallel:
        w.resources[JobPool].close()


def test_run_conditions_are_checked():
    from ecs_engine import any_with

    with pytest.raises(TypeError, match="run_if must be a function of the world"):
        System(run_if=3)
    with pytest.raises(ValueError, match="at least one component type"):
        any_with()
    either = any_with(Velocity) | any_with(Transform, AngularVelocity)
    w = World()
    assert not either(w)
    w.spawn(Transform(), AngularVelocity())
    assert either(w) and repr(either) == "any_with(Velocity) | any_with(Transform, AngularVelocity)"
    empty = World()  # one condition asked of two worlds in turn: each keeps its own answer
    assert not either(empty) and either(w) and not either(empty)


def test_class_system_and_plain_function():
    w = World()
    calls = []

    class Counter(System):
        def __init__(self):
            super().__init__(reads=[Velocity])

        def run(self, world, dt):
            calls.append(dt)

    s = Schedule()
    s.add(Counter())
    s.add(lambda world, dt: calls.append("plain"))
    s.run(w, 0.5)
    assert calls == [0.5, "plain"]
    with pytest.raises(ValueError, match="already scheduled"):
        sys_ = Counter()
        s.add(sys_)
        s.add(sys_)
    with pytest.raises(ValueError, match="unknown stage"):
        s.add(Counter(), "nope")


def test_schedule_cannot_run_inside_a_loop():
    w = World()
    w.spawn(Velocity())
    for _ in w.query(Velocity):
        with pytest.raises(EcsError):
            Schedule().run(w, 0.0)


def test_motion_and_transform_systems():
    w = World()
    e = w.spawn(
        Transform(position=(1, 0, 0)), Velocity(linear=(0, 2, 0)), AngularVelocity(angular=(0, 0, np.pi)), Mesh()
    )
    s = Schedule()
    s.add(MotionSystem())
    ts = s.add(TransformSystem(), "post_update")
    s.run(w, 0.5)
    t = w.get(e, Transform)
    assert np.allclose(t.position, [1, 1, 0])
    # rotated by pi/2 about z: quaternion (0, 0, sin(pi/4), cos(pi/4))
    assert np.allclose(t.rotation, [0, 0, np.sqrt(0.5), np.sqrt(0.5)])
    m = w.get(e, ModelMatrix).model
    assert np.allclose(m[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-6)
    assert np.allclose(m[:3, 3], [1, 1, 0])
    # unchanged transforms are skipped; a moved origin rebuilds everything
    s2 = Schedule()
    s2.add(ts)
    s2.run(w, 0.0)
    assert ts.rows_updated == 0
    w.resources[RenderOrigin] = RenderOrigin(np.array([1.0, 1.0, 0.0]))
    s2.run(w, 0.0)
    assert ts.rows_updated == 1
    assert np.allclose(w.get(e, ModelMatrix).model[:3, 3], [0, 0, 0])


def test_stock_systems_split_across_a_job_pool_give_the_same_result():
    from ecs_engine.jobs import JobPool

    rng = np.random.default_rng(5)
    n = 40_000  # above two chunks, so the pool really splits the tables
    data = dict(
        position=rng.normal(size=(n, 3)),
        rotation=rng.normal(size=(n, 4)),
        linear=rng.normal(size=(n, 3)),
        angular=rng.normal(size=(n, 3)),
    )
    out = []
    for threads in (1, 3):
        w = World()
        w.resources[JobPool] = JobPool(threads)
        w.spawn_batch(
            n,
            Transform(position=data["position"], rotation=data["rotation"]),
            Velocity(linear=data["linear"]),
            AngularVelocity(angular=data["angular"]),
            Mesh(),
        )
        s = Schedule()
        s.add(MotionSystem())
        s.add(TransformSystem(), "post_update")
        for _ in range(3):
            s.run(w, 1 / 30)
        out.append(w.query(ModelMatrix, write=()).column(ModelMatrix.model))
        w.resources[JobPool].close()
    assert np.array_equal(out[0], out[1])


def test_motion_moves_entities_with_either_rate_or_both():
    from ecs_engine.maths.transform import integrate_angular_numpy, integrate_linear_numpy

    rng = np.random.default_rng(8)
    w = World()
    n = 50
    pos, rot = rng.normal(size=(3, n, 3)), rng.normal(size=(3, n, 4))
    rot /= np.linalg.norm(rot, axis=2, keepdims=True)
    lin, ang = rng.normal(size=(3, n, 3)), rng.normal(size=(3, n, 3))
    ids = [
        w.spawn_batch(
            n, Transform(position=pos[0], rotation=rot[0]), Velocity(linear=lin[0]), AngularVelocity(angular=ang[0])
        ),
        w.spawn_batch(n, Transform(position=pos[1], rotation=rot[1]), Velocity(linear=lin[1])),
        w.spawn_batch(n, Transform(position=pos[2], rotation=rot[2]), AngularVelocity(angular=ang[2])),
    ]
    s = Schedule()
    s.add(MotionSystem())
    s.run(w, 0.1)
    for k, (moves, turns) in enumerate([(True, True), (True, False), (False, True)]):
        p, r = pos[k].copy(), rot[k].copy()
        if moves:
            integrate_linear_numpy(p, lin[k], 0.1)
        if turns:
            integrate_angular_numpy(r, ang[k], 0.1)
        got = [w.get(int(e), Transform) for e in ids[k]]
        assert np.allclose([t.position for t in got], p, atol=1e-12)
        assert np.allclose([t.rotation for t in got], r, atol=1e-12)


def test_normal_matrices_are_written_only_for_entities_that_ask_for_them():
    from ecs_engine.components import NormalMatrix, PreviousTransform
    from ecs_engine.ecs.timestep import Interpolation
    from ecs_engine.maths.transform import compose_numpy

    w = World()
    q = np.array([0.1, 0.7, -0.2, 0.6])
    t = Transform(position=(1, 2, 3), rotation=q, scale=(2.0, 0.5, -1.0))
    plain = w.spawn(t, Mesh())
    both = w.spawn(t, Mesh(), NormalMatrix())
    smooth = w.spawn(t, Mesh(), NormalMatrix(), PreviousTransform(position=(1, 2, 3), rotation=q))
    model, normal = np.zeros((1, 4, 4), np.float32), np.zeros((1, 3, 3), np.float32)
    stored = w.get(plain, Transform)
    compose_numpy(stored.position[None], stored.rotation[None], stored.scale[None], np.zeros(3), model, normal)
    w.resources[Interpolation] = Interpolation(0.5)
    w.run_system(TransformSystem(), 0.0)
    for e in (plain, both, smooth):
        assert np.allclose(w.get(e, ModelMatrix).model, model[0], atol=1e-6)
    for e in (both, smooth):
        assert np.allclose(w.get(e, NormalMatrix).normal, normal[0], atol=1e-6)
    assert not w.has(plain, NormalMatrix)
