"""The transform hierarchy (components/hierarchy.py, systems/hierarchy.py): world transforms are
the product of the chain's matrices (scaled, mirrored, far out), follow a parent's move the same
frame, reparenting keeps the world place when asked, subtrees are destroyed whole, loops are
refused, a dead parent leaves a root, and picking sees children where they are drawn."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import EcsError, World, system
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, ModelMatrix, Parent, Transform, WorldMatrix
from ecs_engine.components.hierarchy import children, descendants, destroy_subtree, set_parent
from ecs_engine.maths.decompose import trs_matrices


def q(axis, angle):
    axis = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    return np.r_[axis * np.sin(angle / 2), np.cos(angle / 2)]


def reference(*transforms) -> np.ndarray:
    """The chain's world matrix built independently: T R S products, root first."""
    out = np.eye(4)
    for position, rotation, scale in transforms:
        x, y, z, w = rotation
        r = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        m = np.eye(4)
        m[:3, :3] = r * np.asarray(scale)
        m[:3, 3] = position
        out = out @ m
    return out


CHAIN = [
    ((1.0, 2.0, 3.0), q((0, 1, 0), 0.7), (2.0, 1.0, 0.5)),
    ((0.5, -1.0, 0.0), q((1, 0, 0), -0.4), (1.0, -1.0, 1.0)),  # mirrored
    ((0.0, 0.0, 2.0), q((1, 1, 0), 1.1), (0.3, 0.3, 0.3)),
]


def chain(world: World, offset=(0.0, 0.0, 0.0)) -> list[int]:
    ids: list[int] = []
    for k, (p, r, s) in enumerate(CHAIN):
        position = np.add(p, offset) if k == 0 else p
        parts = [Transform(position=position, rotation=r, scale=s)]
        if ids:
            parts.append(Parent(entity=ids[-1]))
        ids.append(world.spawn(*parts, Mesh()))
    return ids


def test_world_matrices_are_the_chains_product_and_follow_the_root_the_same_frame():
    world = World()
    ids = chain(world)
    schedule = default_schedule()
    schedule.run(world, 0.0)
    want = reference(*CHAIN)
    np.testing.assert_allclose(world.get(ids[2], WorldMatrix).matrix, want, atol=1e-12)
    assert np.linalg.det(want[:3, :3]) < 0  # the mirrored middle link flips the grandchild
    np.testing.assert_allclose(world.get(ids[2], ModelMatrix).model, want, atol=1e-5)
    world.set(ids[0], Transform, position=np.array([10.0, 0.0, 0.0]))
    schedule.run(world, 0.0)
    moved = [((10.0, 0.0, 0.0), CHAIN[0][1], CHAIN[0][2]), *CHAIN[1:]]
    np.testing.assert_allclose(world.get(ids[2], WorldMatrix).matrix, reference(*moved), atol=1e-12)


def test_far_from_the_origin_the_model_matrix_keeps_its_precision():
    from ecs_engine.components import RenderOrigin

    offset = (1e7, -2e7, 3e7)
    world = World()
    ids = chain(world, offset)
    world.resources[RenderOrigin] = RenderOrigin(position=np.array(offset) + (1.0, 2.0, 3.0), follow_camera=False)
    default_schedule().run(world, 0.0)
    want = reference(*CHAIN)  # relative to the origin at the root: the same matrix minus (1, 2, 3)
    want[:3, 3] -= (1.0, 2.0, 3.0)
    np.testing.assert_allclose(world.get(ids[2], ModelMatrix).model, want, atol=1e-5)  # float32, not 1e7 off


def test_reparenting_keeps_the_world_place_when_asked_and_helpers_walk_the_tree():
    """Uniform scales: a world matrix without shear, which a Transform can hold exactly."""
    world = World()
    a = world.spawn(Transform(position=(1.0, 2.0, 3.0), rotation=q((0, 1, 0), 0.7), scale=(2.0, 2.0, 2.0)))
    b = world.spawn(Transform(position=(0.5, -1.0, 0.0), rotation=q((1, 0, 0), -0.4)), Parent(entity=a))
    c = world.spawn(Transform(position=(0.0, 0.0, 2.0), scale=(0.3, 0.3, 0.3)), Parent(entity=b))
    other = world.spawn(Transform(position=(5.0, 5.0, 5.0), rotation=q((0, 0, 1), 0.5), scale=(2.0, 2.0, 2.0)))
    schedule = default_schedule()
    schedule.run(world, 0.0)
    before = world.get(c, WorldMatrix).matrix.copy()
    assert children(world, a).tolist() == [b] and descendants(world, a).tolist() == [b, c]
    set_parent(world, c, other, keep_world=True)
    schedule.run(world, 0.0)
    np.testing.assert_allclose(world.get(c, WorldMatrix).matrix, before, atol=1e-9)
    assert children(world, other).tolist() == [c] and descendants(world, a).tolist() == [b]
    set_parent(world, c, None)  # a root now: its local transform is its world transform
    schedule.run(world, 0.0)
    t = world.get(c, Transform)
    np.testing.assert_allclose(
        world.get(c, WorldMatrix).matrix, trs_matrices(t.position[None], t.rotation[None], t.scale[None])[0]
    )


def test_loops_are_refused_and_a_dead_parent_leaves_a_root():
    world = World()
    a, b, c = chain(world)
    with pytest.raises(EcsError, match="loop"):
        set_parent(world, a, c)
    world.set(a, Parent(entity=c)) if world.has(a, Parent) else world.add(a, Parent(entity=c))  # made anyway
    with pytest.raises(EcsError, match="loops through"):
        default_schedule().run(world, 0.0)
    world.remove(a, Parent)
    world.destroy(b)
    default_schedule().run(world, 0.0)
    local = reference(CHAIN[2])
    np.testing.assert_allclose(world.get(c, WorldMatrix).matrix, local, atol=1e-12)


def test_destroy_subtree_inside_and_outside_a_system():
    world = World()
    a, b, c = chain(world)
    keep = world.spawn(Transform())
    destroy_subtree(world, b)
    assert world.is_alive(a) and not world.is_alive(b) and not world.is_alive(c) and world.is_alive(keep)
    a, b, c = chain(world)

    @system(reads=[Parent])
    def remove(world, dt):
        destroy_subtree(world, a)
        assert world.is_alive(c)  # deferred to the sync point

    from ecs_engine import Schedule

    schedule = Schedule(("update",))
    schedule.add(remove)
    schedule.run(world, 0.0)
    assert not any(world.is_alive(e) for e in (a, b, c)) and world.is_alive(keep)


def test_a_wide_hierarchy_matches_each_entitys_own_product():
    rng = np.random.default_rng(2)
    world = World()
    roots = world.spawn_batch(50, Transform(position=rng.uniform(-10, 10, (50, 3)), scale=rng.uniform(0.5, 2, (50, 3))))
    n = 2000
    parent_of = roots[rng.integers(0, 50, n)]
    rotation = rng.normal(size=(n, 4))
    kids = world.spawn_batch(
        n, Transform(position=rng.uniform(-3, 3, (n, 3)), rotation=rotation), Parent(entity=parent_of)
    )
    grand = world.spawn_batch(n, Transform(position=(0.0, 1.0, 0.0)), Parent(entity=kids))
    default_schedule().run(world, 0.0)
    for k in rng.integers(0, n, 20):
        g, kid, root = grand[k], kids[k], parent_of[k]
        parts = [world.get(e, Transform) for e in (root, kid, g)]
        want = reference(*[(t.position, t.rotation, t.scale) for t in parts])
        np.testing.assert_allclose(world.get(g, WorldMatrix).matrix, want, atol=1e-9)


def test_picking_finds_a_child_where_its_parent_puts_it():
    from test_picking import Registry, pixel_of

    from ecs_engine.demos.scene_kit import add_camera
    from ecs_engine.render.assets.primitives import cube_mesh
    from ecs_engine.render.picking import pick

    world = World()
    add_camera(world, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0))
    parent = world.spawn(Transform(position=(2.0, 0.0, 0.0), rotation=q((0, 0, 1), np.pi / 2)))
    child = world.spawn(Transform(position=(1.0, 0.0, 0.0)), Parent(entity=parent), Mesh())
    default_schedule().run(world, 0.0)
    # rotated 90 degrees about z, the child's local +x offset lands at world (2, 1, 0)
    hit = pick(world, Registry(cube_mesh()), *pixel_of(world, np.array([2.0, 1.0, 0.0])), 96, 64)
    assert hit is not None and hit.entity == child
    assert pick(world, Registry(cube_mesh()), *pixel_of(world, np.array([3.0, 0.0, 0.0])), 96, 64) is None


def test_the_compiled_and_numpy_paths_agree(monkeypatch):
    from ecs_engine import native
    from ecs_engine.systems import HierarchySystem

    if not native.AVAILABLE:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    rng = np.random.default_rng(5)
    world = World()
    roots = world.spawn_batch(20, Transform(position=rng.normal(size=(20, 3)), scale=rng.uniform(0.5, 2, (20, 3))))
    kids = world.spawn_batch(
        500,
        Transform(position=rng.normal(size=(500, 3)), rotation=rng.normal(size=(500, 4))),
        Parent(entity=roots[rng.integers(0, 20, 500)]),
    )
    world.spawn_batch(500, Transform(scale=(-1.0, 2.0, 1.0)), Parent(entity=kids))
    world.spawn_batch(10, Parent(entity=kids[:10]))  # no Transform: identity under its parent
    system = HierarchySystem()
    world.run_system(system, 0.0)
    compiled = world.query(WorldMatrix).column(WorldMatrix.matrix)
    monkeypatch.setattr(native, "AVAILABLE", False)
    world.run_system(system, 0.0)
    np.testing.assert_allclose(world.query(WorldMatrix).column(WorldMatrix.matrix), compiled, atol=1e-12)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_kept_plan_follows_every_change_it_depends_on(compiled, monkeypatch):
    """The system keeps its plan while the hierarchy is still: moved parents are followed without
    planning again, an unrelated spawn keeps the plan, and a reparent, a parent destroyed, a
    parent gaining a Transform or parents in another table each make a new one that is right."""
    from ecs_engine import native
    from ecs_engine.components import Velocity
    from ecs_engine.systems import HierarchySystem

    if compiled and not native.AVAILABLE:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    monkeypatch.setattr(native, "AVAILABLE", compiled)

    world, system = World(), HierarchySystem()
    a = world.spawn(Transform(position=(1.0, 0.0, 0.0)))
    b = world.spawn(Transform(position=(0.0, 5.0, 0.0)), Velocity())  # another table
    bare = world.spawn(Velocity())  # no Transform: the identity, until it gains one
    kids = world.spawn_batch(3, Transform(position=(0.0, 0.0, 1.0)), Parent(entity=np.array([a, a, bare])))

    def where() -> np.ndarray:
        world.run_system(system, 0.0)
        return np.array([world.get(k, WorldMatrix).matrix[:3, 3] for k in kids])

    np.testing.assert_allclose(where(), [[1, 0, 1], [1, 0, 1], [0, 0, 1]])
    plan = system.plan(world)
    world.set(a, Transform, position=np.array([2.0, 0.0, 0.0]))
    world.spawn_batch(10, Transform(), Velocity())  # b's table changes; no kid's parent is there yet
    np.testing.assert_allclose(where(), [[2, 0, 1], [2, 0, 1], [0, 0, 1]])
    assert system.plan(world) is plan
    world.set(kids[1], Parent, entity=b)  # a Parent column written
    np.testing.assert_allclose(where(), [[2, 0, 1], [0, 5, 1], [0, 0, 1]])
    world.add(bare, Transform(position=(0.0, 0.0, -3.0)))
    np.testing.assert_allclose(where(), [[2, 0, 1], [0, 5, 1], [0, 0, -2]])
    world.set(b, Transform, position=np.array([0.0, 7.0, 0.0]))  # a second outside table, followed
    np.testing.assert_allclose(where()[1], [0, 7, 1])
    world.destroy(a)
    np.testing.assert_allclose(where(), [[0, 0, 1], [0, 7, 1], [0, 0, -2]])


def test_levels_cut_into_chunks_on_the_pool_give_the_same_matrices():
    from ecs_engine import native
    from ecs_engine.jobs import CHUNK_ROWS, JobPool
    from ecs_engine.systems import HierarchySystem

    if not native.AVAILABLE:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    rng = np.random.default_rng(8)
    n = 3 * CHUNK_ROWS

    def worlds(pool):
        world = World()
        if pool is not None:
            world.resources[JobPool] = pool
        roots = world.spawn_batch(100, Transform(position=rng.normal(size=(100, 3))))
        kids = world.spawn_batch(
            n, Transform(position=rng.normal(size=(n, 3))), Parent(entity=roots[np.arange(n) % 100])
        )
        world.spawn_batch(n, Transform(position=(0.0, 1.0, 0.0)), Parent(entity=kids))
        world.run_system(HierarchySystem(), 0.0)
        return world.query(WorldMatrix).column(WorldMatrix.matrix)

    rng = np.random.default_rng(8)
    alone = worlds(None)
    rng = np.random.default_rng(8)
    with JobPool(4) as pool:
        np.testing.assert_array_equal(worlds(pool), alone)


def test_one_tree_and_a_forest_give_the_same_matrices_on_the_pool_as_alone():
    """The compiled pass cuts one wide tree into chunks of a level at a time and a forest (a crowd)
    into jobs of whole trees (systems/hierarchy.py's _tree_jobs): both equal the pass on one
    thread, bit for bit, three levels deep."""
    from ecs_engine import native
    from ecs_engine.jobs import CHUNK_ROWS, JobPool
    from ecs_engine.systems import HierarchySystem

    if not native.AVAILABLE:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    n = 3 * CHUNK_ROWS

    def worlds(pool, trees):
        rng = np.random.default_rng(9)
        world = World()
        if pool is not None:
            world.resources[JobPool] = pool
        roots = world.spawn_batch(trees, Transform(position=rng.normal(size=(trees, 3))))
        kids = world.spawn_batch(
            n, Transform(position=rng.normal(size=(n, 3)), scale=rng.uniform(0.5, 2, (n, 3))),
            Parent(entity=roots[rng.integers(0, trees, n)]),
        )  # fmt: skip
        world.spawn_batch(n, Transform(position=(0.0, 1.0, 0.0)), Parent(entity=kids[rng.permutation(n)]))
        world.run_system(HierarchySystem(), 0.0)
        return world.query(WorldMatrix).column(WorldMatrix.matrix)

    for trees in (1, 500):
        alone = worlds(None, trees)
        with JobPool(4) as pool:
            np.testing.assert_array_equal(worlds(pool, trees), alone)
