"""The engine's own rays against primitive shapes (ecs_engine/physics/ray_grid.py), checked
against a reference that shares none of its code: each ray marched in millimetre steps, the
first step found inside a shape by the shapes' inside tests written out in NumPy."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import native
from ecs_engine.components.physics import BOX, CAPSULE, CYLINDER, SPHERE

pytestmark = pytest.mark.skipif(not native.AVAILABLE, reason="the engine's rays are compiled with numba")
STEP = 1e-3  # the march's step (m)


def matrices(q):
    x, y, z, w = (q / np.linalg.norm(q, axis=1)[:, None]).T
    return np.stack(
        [
            np.c_[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            np.c_[2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            np.c_[2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ],
        axis=1,
    )


def inside(points, centre, turn, shape, size):
    """(T, S): whether each point is inside each shape (its Collider's sizes: half extents; or
    radius, half height along the local y)."""
    local = np.einsum("sji,tsj->tsi", turn, points[:, None, :] - centre[None])
    x, y, z = local[..., 0], local[..., 1], local[..., 2]
    r, h = size[:, 0], size[:, 1]
    box = (abs(x) <= size[:, 0]) & (abs(y) <= size[:, 1]) & (abs(z) <= size[:, 2])
    ball = x * x + y * y + z * z <= r * r
    along = np.clip(y, -h, h)
    capsule = x * x + (y - along) ** 2 + z * z <= r * r
    cylinder = (x * x + z * z <= r * r) & (abs(y) <= h)
    return np.select([shape == BOX, shape == SPHERE, shape == CAPSULE], [box, ball, capsule], cylinder)


def marched(origin, direction, reach, centre, turn, shape, size):
    """The first step along the ray inside a shape: (distance, the shapes there), or None."""
    bound = np.where(shape == BOX, np.linalg.norm(size, axis=1), size[:, 0] + size[:, 1])
    offset = centre - origin
    along = np.clip(offset @ direction, 0.0, reach)
    near = np.flatnonzero(np.linalg.norm(offset - along[:, None] * direction, axis=1) <= bound)
    if not len(near):
        return None
    steps = np.arange(0.0, reach, STEP)
    within = inside(origin + steps[:, None] * direction, centre[near], turn[near], shape[near], size[near])
    first = np.flatnonzero(within.any(axis=1))
    if not len(first):
        return None
    return steps[first[0]], near[within[first[0]]]


def scene(count, spread, seed):
    """`count` shapes of every kind, turned at random, as the library's buffers hold them, and a
    floor larger than the grid's cells."""
    rng = np.random.default_rng(seed)
    positions = np.zeros((count, 4))
    positions[:, :3] = rng.uniform(-spread, spread, (count, 3))
    rotations = rng.normal(size=(count, 4)).astype(np.float32)
    shape = rng.choice([BOX, SPHERE, CAPSULE, CYLINDER], count)
    size = rng.uniform(0.15, 0.6, (count, 3))
    shape[0], size[0], positions[0, :3], rotations[0] = (
        BOX,
        (3 * spread, 0.5, 3 * spread),
        (0, -spread - 2, 0),
        (
            0,
            0,
            0,
            1,
        ),
    )
    return positions, rotations, shape, size


def test_rays_meet_the_shape_a_march_finds_first_at_its_distance():
    from ecs_engine.physics.ray_grid import RayGrid, Shapes

    positions, rotations, shape, size = scene(400, 6.0, 5)
    grid = RayGrid.build(
        Shapes.of(np.arange(400) + 1000, np.arange(400), shape, size, np.zeros(400, bool)), positions, rotations
    )
    assert list(grid.shapes.large) == [0]  # the floor: every ray tests it
    rng = np.random.default_rng(6)
    count, reach = 240, 25.0
    origins = rng.uniform(-8.0, 8.0, (count, 3))
    directions = rng.normal(size=(count, 3))
    directions[::3] = np.eye(3)[rng.integers(0, 3, count // 3)] * rng.choice([-1.0, 1.0], (count // 3, 1))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    directions *= rng.uniform(0.5, 3.0, (count, 1))  # (any length: the cast makes them unit)
    index, distance, point, normal = (
        np.empty(count, np.int64),
        np.empty(count),
        np.empty((count, 3)),
        np.empty((count, 3)),
    )
    grid.cast(origins, directions, reach, (index, distance, point, normal))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    centre, turn = positions[:, :3], matrices(rotations.astype(np.float64))
    met = 0
    for k in range(count):
        found = marched(origins[k], directions[k], reach, centre, turn, shape, size)
        if found is None:
            assert index[k] == -1 and np.isnan(distance[k]) and np.isnan(point[k]).all()
            continue
        met += 1
        at, shapes = found
        assert index[k] in shapes, k
        assert distance[k] == pytest.approx(at, abs=1.5 * STEP)
        assert np.allclose(point[k], origins[k] + directions[k] * distance[k])
        if at > 0:  # the normal: unit, against the ray, and pointing out of the shape
            n = normal[k]
            assert np.linalg.norm(n) == pytest.approx(1.0)
            assert n @ directions[k] <= 1e-9
            out = origins[k] + directions[k] * distance[k] + n * 2 * STEP
            assert not inside(out[None], centre[[index[k]]], turn[[index[k]]], shape[[index[k]]], size[[index[k]]])[
                0, 0
            ]
        else:
            assert normal[k] @ directions[k] == pytest.approx(-1.0)
    assert met > 60


def test_the_grid_holds_every_shape_in_every_cell_its_bounds_touch():
    """A pile's worth of boxes: a ray down every column hits the top one, none slipping between
    cells (the same answer as testing every box)."""
    from ecs_engine.physics.ray_grid import RayGrid, Shapes

    side = 30
    x, z = np.meshgrid(np.arange(side) * 1.1, np.arange(side) * 1.1)
    count = side * side * 3
    positions = np.zeros((count, 4))
    positions[:, 0], positions[:, 2] = np.tile(x.ravel(), 3), np.tile(z.ravel(), 3)
    positions[:, 1] = np.repeat([0.5, 1.5, 2.5], side * side)
    rotations = np.tile(np.float32((0, 0, 0, 1)), (count, 1))
    shapes = Shapes.of(
        np.arange(count), np.arange(count), np.full(count, BOX), np.full((count, 3), 0.5), np.zeros(count, bool)
    )
    grid = RayGrid.build(shapes, positions, rotations)
    origins = np.c_[x.ravel(), np.full(side * side, 10.0), z.ravel()]
    down = np.tile((0.0, -1.0, 0.0), (side * side, 1))
    index, distance = np.empty(side * side, np.int64), np.empty(side * side)
    point, normal = np.empty((side * side, 3)), np.empty((side * side, 3))
    grid.cast(origins, down, 50.0, (index, distance, point, normal))
    assert (index == np.arange(side * side) + 2 * side * side).all()  # the top layer's box below each
    assert np.allclose(distance, 7.0) and np.allclose(normal, (0.0, 1.0, 0.0))


def _cast(grid, origins, directions, jobs, pool):
    count = len(origins)
    out = (np.full(count, -7, np.int64), np.empty(count), np.empty((count, 3)), np.empty((count, 3)))
    shared = claims()
    pool.map(lambda _: grid.cast(origins, directions, 20.0, out, shared), range(jobs))
    return out


def claims():
    from ecs_engine.physics.ray_walk import claims

    return claims()


def test_threads_sharing_a_cast_take_every_ray_once_and_answer_as_one_thread_does():
    """Rays spread over a JobPool's threads through shared counters, or over numba's threads:
    every ray is cast (a count that is no multiple of the block), with the same answers as one
    thread."""
    from ecs_engine.jobs import JobPool
    from ecs_engine.physics.ray_grid import RayGrid, Shapes

    positions, rotations, shape, size = scene(300, 5.0, 8)
    grid = RayGrid.build(
        Shapes.of(np.arange(300), np.arange(300), shape, size, np.zeros(300, bool)), positions, rotations
    )
    rng = np.random.default_rng(9)
    origins, directions = rng.uniform(-7.0, 7.0, (1001, 3)), rng.normal(size=(1001, 3))
    with JobPool(4) as pool:
        alone, together = _cast(grid, origins, directions, 1, pool), _cast(grid, origins, directions, 4, pool)
    assert (alone[0] != -7).all() and (alone[0] >= 0).sum() > 300
    for a, b in zip(alone, together):
        assert np.array_equal(a, b, equal_nan=True)
    # on numba's own threads (native.parallel), each shape answered as `answer` says
    answer = 10 * np.arange(300) + 7
    spread = (np.full(1001, -7, np.int64), np.empty(1001), np.empty((1001, 3)), np.empty((1001, 3)))
    grid.cast(origins, directions, 20.0, spread, answer=answer, jobs=3)
    assert np.array_equal(spread[0], np.where(alone[0] >= 0, answer[alone[0]], alone[0]))
    for a, b in zip(alone[1:], spread[1:]):
        assert np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("fused", [False, True])
def test_shapes_that_moved_past_the_margin_are_moved_into_their_new_cells_as_a_new_grid_has_them(fused):
    """Shapes moved and turned (within the grid's box), the grid refreshed: every ray answers
    as on a grid made anew. A shape that leaves the box, or more shapes in a cell than it has
    room for, is tested by every ray instead, the same answers again; past ray_refresh.SPILL
    such shapes the grid is to be made again (False). Static bodies' shapes are looked at only
    when asked (a body was put somewhere). `fused`: the refresh and a cast in one kernel on
    numba's threads (refresh_and_cast), its rays answering as on the new grid, none cast where
    the grid is to be made again."""
    from ecs_engine.jobs import JobPool
    from ecs_engine.physics.ray_grid import RayGrid, Shapes

    positions, rotations, shape, size = scene(400, 5.0, 10)
    still = np.arange(400) % 2 == 0  # static bodies' shapes: looked at only when bodies were put somewhere
    shapes = Shapes.of(np.arange(400), np.arange(400), shape, size, still)
    grid = RayGrid.build(shapes, positions, rotations)
    rng = np.random.default_rng(11)
    moved = rng.choice(np.arange(1, 400), 30, replace=False)
    positions[moved, :3] += rng.uniform(-0.8, 0.8, (30, 3))
    rotations[moved[:15]] = rng.normal(size=(15, 4))
    stays = moved[-1]  # (within the margin: left in its cells)
    positions[stays, :3] = grid.centre[stays] + (0.5 * grid.margin, 0.0, 0.0)
    origins, directions = rng.uniform(-7.0, 7.0, (2000, 3)), rng.normal(size=(2000, 3))

    def bring(everything=True):
        if not fused:
            return grid.refresh(everything=everything)
        out, shared = (np.full(2000, -7, np.int64), np.empty(2000), np.empty((2000, 3)), np.empty((2000, 3))), claims()
        done = grid.refresh_and_cast(everything, 3, origins, directions, 20.0, out, shared, 10 * np.arange(400))
        if done and everything:  # (else a static shape put elsewhere is not looked at, by design)
            fresh = (np.empty(2000, np.int64), np.empty(2000), np.empty((2000, 3)), np.empty((2000, 3)))
            new = RayGrid.build(shapes, positions, rotations)
            new.cast(origins, directions, 20.0, fresh, answer=10 * np.arange(400))
            for a, b in zip(out, fresh):
                assert np.array_equal(a, b, equal_nan=True)
        assert shared[0] >= len(origins) if done else shared[0] == 0  # (every ray taken, or none)
        return done

    def same_as_a_new_grid(pool):
        fresh = RayGrid.build(shapes, positions, rotations)
        ours, theirs = _cast(grid, origins, directions, 4, pool), _cast(fresh, origins, directions, 1, pool)
        assert (ours[0] >= 0).sum() > 500
        for a, b in zip(ours, theirs):
            assert np.array_equal(a, b, equal_nan=True)
        return fresh

    with JobPool(4) as pool:
        assert bring()
        assert (
            np.array_equal(grid.centre[moved[:-1]], positions[moved[:-1], :3])
            and (grid.centre[stays] != positions[stays, :3]).any()
        )
        fresh = same_as_a_new_grid(pool)
        assert grid.fill.sum() == fresh.fill.sum() and grid.spill[0] == 0  # no shape left behind in a cell it left
        away = moved[0]  # out of the grid's box: spilt, tested by every ray
        positions[away, 1] = grid.origin[1] + grid.dims[1] * grid.cell + 1.0
        crowd = moved[1:6]  # five more into one shape's cells: some find a cell full
        positions[crowd, :3] = positions[moved[6], :3]
        assert bring()
        assert away in grid.spill[1 : grid.spill[0] + 1] and grid.spill[0] > 1
        same_as_a_new_grid(pool)
        above = _cast(grid, positions[[away], :3] + (0.0, 5.0, 0.0), np.array([[0.0, -1.0, 0.0]]), 1, pool)
        assert above[0][0] == away
        positions[away, :3] = grid.centre[moved[7]] + 0.1  # back in: out of the spill again
        assert bring()
        assert away not in grid.spill[1 : grid.spill[0] + 1]
        same_as_a_new_grid(pool)
        put = 2 * np.flatnonzero(np.arange(2, 400, 2) % 7 == 0)[0] + 2  # a static shape, put elsewhere
        positions[put, :3] = positions[moved[8], :3] + 0.3
        assert bring(everything=False) and (grid.centre[put] != positions[put, :3]).all()
        assert bring(everything=True) and (grid.centre[put] == positions[put, :3]).all()
        same_as_a_new_grid(pool)
    positions[1:200, :3] = positions[200, :3]  # 199 shapes into one shape's cells: past the spill
    assert not bring()


def test_a_grid_made_by_threads_holds_what_one_thread_makes(monkeypatch):
    """Made over a JobPool (the threads taking blocks of shapes and each cell's slots at once),
    every cell holds the same shapes as when one thread makes it (in any order), and every ray
    answers alike."""
    import ecs_engine.physics.ray_grid as ray_grid
    from ecs_engine.jobs import JobPool
    from ecs_engine.physics.ray_grid import RayGrid, Shapes

    monkeypatch.setattr(ray_grid, "SHARED_BUILD", 0)
    monkeypatch.setattr(ray_grid, "BLOCK", 64)
    positions, rotations, shape, size = scene(900, 8.0, 12)
    shapes = Shapes.of(np.arange(900), np.arange(900), shape, size, np.zeros(900, bool))
    rng = np.random.default_rng(13)
    origins, directions = rng.uniform(-10.0, 10.0, (1500, 3)), rng.normal(size=(1500, 3))
    with JobPool(4) as pool:
        alone, together = RayGrid.build(shapes, positions, rotations), RayGrid.build(shapes, positions, rotations, pool)
        assert np.array_equal(alone.starts, together.starts) and np.array_equal(alone.fill, together.fill)
        for c in np.flatnonzero(alone.fill):
            first, last = alone.starts[c], alone.starts[c] + alone.fill[c]
            assert sorted(alone.items[first:last]) == sorted(together.items[first:last]), c
        ours, theirs = _cast(together, origins, directions, 4, pool), _cast(alone, origins, directions, 1, pool)
    assert (ours[0] >= 0).sum() > 300
    for a, b in zip(ours, theirs):
        assert np.array_equal(a, b, equal_nan=True)


def test_openmps_threads_sleep_as_soon_as_the_rays_are_cast():
    """On numba's OpenMP layer the rays' threads are told to sleep when a kernel ends
    (OMP_WAIT_POLICY, set by native.spread unless set before): the process spends next to no CPU
    time in the 50 ms after a cast. By default libgomp's threads spin for milliseconds (7.5 ms of
    CPU in those 50 on the lavapipe host's 2 cores), taking cores from what runs next."""
    import os
    import time

    import numba

    from ecs_engine.physics.ray_grid import RayGrid, Shapes

    positions, rotations, shape, size = scene(60, 3.0, 4)
    grid = RayGrid.build(Shapes.of(np.arange(60), np.arange(60), shape, size, np.zeros(60, bool)), positions, rotations)
    rng = np.random.default_rng(3)
    origins, directions = rng.uniform(-4.0, 4.0, (256, 3)), rng.normal(size=(256, 3))
    out = (np.empty(256, np.int64), np.empty(256), np.empty((256, 3)), np.empty((256, 3)))
    grid.cast(origins, directions, 10.0, out, jobs=2)
    if numba.threading_layer() != "omp" or numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip(f"numba's threads here are {numba.threading_layer()}'s, which do not spin")
    assert os.environ.get("OMP_WAIT_POLICY", "PASSIVE").upper() == "PASSIVE"
    spent = []
    for _ in range(3):
        grid.cast(origins, directions, 10.0, out, jobs=2)
        before = time.process_time()
        time.sleep(0.05)
        spent.append(time.process_time() - before)
    assert min(spent) < 0.003, spent
