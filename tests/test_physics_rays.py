"""PhysicsWorld.raycast: the engine's rays against the bodies' primitive shapes agree with the
library's own batch, follow the bodies as they move, and leave meshes and terrain to the
library, whichever is nearer answering."""

from __future__ import annotations

import numpy as np
import pytest
from physics_world import ball, floor, physics_plugin, simulate

from ecs_engine import native
from ecs_engine.components import Mesh, Transform
from ecs_engine.components.physics import BOX, CAPSULE, CYLINDER, DYNAMIC, MESH, SPHERE, STATIC, Collider, RigidBody

pytestmark = pytest.mark.skipif(not native.AVAILABLE, reason="the engine's rays are compiled with numba")


def library(physics, origins, directions, reach):
    from ecs_engine.physics.queries import _library_rays

    unit = directions / np.linalg.norm(directions, axis=1)[:, None]
    return _library_rays(physics, np.asarray(origins, np.float64), unit, reach)


def test_rays_agree_with_the_library_on_turned_shapes_of_every_kind():
    rng = np.random.default_rng(11)
    kinds = [BOX, SPHERE, CAPSULE, CYLINDER]

    def setup(world, dt):
        for i in range(120):
            q = rng.normal(size=4)
            world.spawn(
                Transform(position=tuple(rng.uniform(-6, 6, 3)), rotation=tuple(q / np.linalg.norm(q))),
                RigidBody(kind=STATIC),
                Collider(shape=kinds[i % 4], size=tuple(rng.uniform(0.2, 0.8, 3))),
            )

    _, physics = simulate(setup, 1)
    origins = rng.uniform(-8, 8, (3000, 3))
    directions = rng.normal(size=(3000, 3))
    hits = physics.raycast(origins, directions, 30.0)
    theirs = library(physics, origins, directions, 30.0)
    entity, distance, normal = theirs.entity, theirs.distance, theirs.normal
    assert (hits.entity >= 0).sum() > 500
    # the library casts in float32: rays that graze a shape (the two distances apart) may differ
    same = hits.entity == entity
    assert same.mean() > 0.99
    both = same & (entity >= 0)
    assert np.allclose(hits.distance[both], distance[both], atol=2e-4)
    met = both & (hits.distance > 0)
    assert np.allclose(hits.normal[met], normal[met], atol=2e-3)


def test_rays_follow_the_bodies_as_they_fall_and_as_they_are_placed():
    made = {}

    def setup(world, dt):
        floor(world)
        made["ball"] = ball(world, 10.0)

    world, physics = simulate(setup, 1)
    down = [(0.0, -1.0, 0.0)]
    for _ in range(30):
        physics.step(1 / 60)
        top = physics.bodies.position_of(made["ball"])[1] + 0.5
        hits = physics.raycast([(0.0, 20.0, 0.0)], down, 50.0)
        assert hits.entity[0] == made["ball"] and hits.distance[0] == pytest.approx(20.0 - top, abs=1e-5)
    column, row = _transform_row(world, made["ball"])
    column.position[row] = (5.0, 2.0, 0.0)  # a teleport, as PhysicsSystem makes it of a Transform written
    physics.place(np.array([made["ball"]]), column, np.array([row]))
    hits = physics.raycast([(5.0, 20.0, 0.0), (0.0, 20.0, 0.0)], down * 2, 50.0)
    assert hits.entity[0] == made["ball"] and hits.distance[0] == pytest.approx(17.5, abs=1e-5)
    assert hits.distance[1] == pytest.approx(20.0, abs=1e-5)  # where it was: the floor


def test_rays_see_a_static_body_where_it_is_put_and_follow_one_made_dynamic():
    """Static bodies' shapes are looked at only after a body was put somewhere: a static box put
    elsewhere is met there, and one a system makes dynamic is followed as it falls."""
    from ecs_engine import App, MinimalPlugins, Time
    from ecs_engine.physics import PhysicsWorld

    made, seen = {}, []

    def setup(world, dt):
        floor(world)
        for k, x in enumerate((-4.0, 4.0)):
            made[k] = world.spawn(Transform(position=(x, 3.0, 0.0)), RigidBody(kind=STATIC), Collider(shape=BOX))

    def look(world, dt):
        physics, step = world.resources[PhysicsWorld], world.resources[Time].steps
        hits = physics.raycast([(-2.0, 20.0, 0.0), (-4.0, 20.0, 0.0), (4.0, 20.0, 0.0)], [(0.0, -1.0, 0.0)] * 3, 50.0)
        seen.append((step, hits, float(world.get(made[1], Transform).position[1])))
        if step == 5:
            column, row = _transform_row(world, made[0])
            column.position[row] = (
                -2.0,
                5.0,
                0.0,
            )  # put elsewhere, as PhysicsSystem puts a body whose Transform a system wrote
            physics.place(np.array([made[0]]), column, np.array([row]))
        if step == 15:  # (later: a body made dynamic has the grid made again)
            world.set(made[1], RigidBody, kind=DYNAMIC)

    app = App(title="static rays").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", look)
    app.run(frames=50)
    for step, hits, y in seen:
        if step <= 6:  # (before the change reached the bodies)
            continue
        assert hits.entity[0] == made[0] and hits.distance[0] == pytest.approx(14.5, abs=1e-5)
        assert hits.entity[1] != made[0]  # not where it was
        assert hits.entity[2] == made[1] and hits.distance[2] == pytest.approx(19.5 - y, abs=1e-4)
    assert seen[10][2] == 3.0
    assert seen[-1][2] < 2.0  # it fell


def _transform_row(world, entity):
    """The Transform column holding `entity`'s row, writable, and the row."""
    for batch in world.query(Transform, write=(Transform,)):
        if entity in batch.entities:
            return batch[Transform], int(np.flatnonzero(batch.entities == entity)[0])
    raise AssertionError(entity)


def test_a_mesh_collider_is_hit_where_it_is_nearer_than_the_shapes():
    from ecs_engine.render import Meshes, plane_mesh

    made = {}

    def setup(world, dt):
        ground = world.resources[Meshes].add(plane_mesh(size=1.0, subdivisions=4))
        made["plane"] = world.spawn(  # a 20 m plane at y = 1
            Transform(position=(0.0, 1.0, 0.0), scale=(20.0, 1.0, 20.0)),
            Mesh(handle=ground),
            RigidBody(kind=STATIC),
            Collider(shape=MESH),
        )
        made["above"] = world.spawn(Transform(position=(3.0, 3.0, 0.0)), RigidBody(kind=STATIC), Collider(shape=BOX))
        made["below"] = world.spawn(Transform(position=(-3.0, -2.0, 0.0)), RigidBody(kind=STATIC), Collider(shape=BOX))

    _, physics = simulate(setup, 1)
    origins = [(3.0, 10.0, 0.0), (-3.0, 10.0, 0.0), (-3.0, -10.0, 0.0), (30.0, 10.0, 0.0)]
    directions = [(0.0, -1.0, 0.0)] * 3 + [(0.0, -1.0, 0.0)]
    directions[2] = (0.0, 1.0, 0.0)
    hits = physics.raycast(origins, directions, 50.0)
    assert hits.entity.tolist() == [made["above"], made["plane"], made["below"], -1]
    assert np.allclose(hits.distance[:3], [6.5, 9.0, 7.5], atol=1e-4)
    assert np.allclose(hits.point[1], (-3.0, 1.0, 0.0), atol=1e-4)


@pytest.mark.parametrize(
    ("origin", "direction", "says"),
    [
        ((0.0, np.nan, 0.0), (0.0, -1.0, 0.0), r"origins and directions must be finite \(ray 1 is not\)"),
        ((0.0, 5.0, 0.0), (0.0, np.inf, 0.0), r"origins and directions must be finite \(ray 1 is not\)"),
        ((0.0, 5.0, 0.0), (0.0, 0.0, 0.0), "direction 1 has zero length"),
    ],
)
def test_a_ray_that_is_not_finite_or_has_no_direction_is_one_error(origin, direction, says):
    _, physics = simulate(lambda world, dt: floor(world), 1)
    with pytest.raises(ValueError, match=says):
        physics.raycast([(0.0, 5.0, 0.0), origin], [(0.0, -1.0, 0.0), direction], 10.0)


def test_the_grid_follows_a_moving_shape_into_new_cells_and_past_its_box():
    """A box gliding through space at 0.3 m/s past resting ones: the grid is kept, the box moved
    into the cells it reaches each time it has gone further than the grid's margin, and every
    ray meets it where it is at that step. Sent far off, past the grid's box, every ray tests
    it instead."""
    made = {}

    def setup(world, dt):
        for x in range(-6, 7, 2):
            world.spawn(Transform(position=(float(x), 0.0, -3.0)), RigidBody(kind=STATIC), Collider(shape=BOX))
        made["box"] = world.spawn(Transform(position=(-4.0, 0.0, 0.0)), RigidBody(), Collider(shape=BOX))

    _, physics = simulate(setup, 1, gravity=(0.0, 0.0, 0.0))
    physics.set_velocity(made["box"], (0.3, 0.0, 0.0))
    grid = physics.ray_grid()[0]
    box = int(np.flatnonzero(grid.shapes.entity == made["box"])[0])
    noted = set()
    for _ in range(40):
        physics.step(1 / 60)
        x = physics.bodies.position_of(made["box"])[0]
        hits = physics.raycast([(x - 0.3, 5.0, 0.0), (x + 0.6, 5.0, 0.0)], [(0.0, -1.0, 0.0)] * 2, 10.0)
        assert hits.entity[0] == made["box"] and hits.distance[0] == pytest.approx(4.5, abs=1e-6)
        assert hits.entity[1] == -1  # just past its leading face
        assert physics.ray_grid()[0] is grid
        noted.add(float(grid.centre[box, 0]))
    assert len(noted) > 3 and physics.grids_made == 1  # moved into new cells now and then, never made again
    physics.set_velocity(made["box"], (0.0, 0.0, 300.0))
    physics.step(1 / 60)
    x, _, z = physics.bodies.position_of(made["box"])
    assert z > grid.origin[2] + grid.dims[2] * grid.cell
    hits = physics.raycast([(x, 5.0, z)], [(0.0, -1.0, 0.0)], 10.0)
    assert hits.entity[0] == made["box"] and physics.grids_made == 1
    assert box in grid.spill[1 : grid.spill[0] + 1]  # tested by every ray, outside the cells


def test_many_rays_bring_the_grid_up_and_are_cast_in_one_kernel_on_numbas_threads(monkeypatch):
    """Over 1,000 rays with the world's JobPool: the grid's refresh and the cast run in one
    kernel on numba's threads (ray_spread.py), step after step as boxes tumble onto a floor,
    each ray answering as on a grid made anew, the grid kept."""
    from ecs_engine.jobs import JobPool
    from ecs_engine.physics import ray_grid
    from ecs_engine.physics.ray_grid import RayGrid

    fused = []
    kernel = ray_grid.refresh_and_spread

    def counted(jobs, counters, shapes, *rays):  # (the shapes looked at: shapes[3]; none for a cast alone)
        if len(shapes[3]):
            fused.append(jobs)
        return kernel(jobs, counters, shapes, *rays)

    monkeypatch.setattr(ray_grid, "refresh_and_spread", counted)

    def setup(world, dt):
        floor(world)
        for k in range(40):
            q = np.array([0.3 * k, 1.0, 0.2, 1.0])
            where = (0.9 * (k % 6) - 2.2, 1.0 + 0.8 * (k // 6), 0.7 * (k % 4) - 1.0)
            world.spawn(
                Transform(position=where, rotation=tuple(q / np.linalg.norm(q))), RigidBody(), Collider(shape=BOX)
            )

    _, physics = simulate(setup, 1)
    physics.pool = JobPool(3)
    x, z = np.meshgrid(np.linspace(-3.5, 3.5, 40), np.linspace(-2.5, 2.5, 30))
    origins = np.c_[x.ravel(), np.full(x.size, 12.0), z.ravel()]
    down = np.tile((0.0, -1.0, 0.0), (len(origins), 1))
    physics.raycast(origins, down, 50.0)
    grid = physics.ray_grid()[0]
    for _ in range(25):
        physics.step(1 / 60)
        hits = physics.raycast(origins, down, 50.0)
        positions, rotations, _, _ = physics.buffers()
        fresh = (
            np.empty(len(origins), np.int64),
            np.empty(len(origins)),
            np.empty((len(origins), 3)),
            np.empty((len(origins), 3)),
        )
        RayGrid.build(grid.shapes, positions, rotations).cast(origins, down, 50.0, fresh, answer=grid.shapes.entity)
        assert np.array_equal(hits.entity, fresh[0]) and np.array_equal(hits.distance, fresh[1], equal_nan=True)
    physics.pool.close()
    assert len(fused) == 25 and min(fused) > 1 and physics.ray_grid()[0] is grid
    assert (hits.entity >= 0).sum() > 300
