"""Temporal-coherence culling (maths/coherence.py, render/culling/temporal_culling.py): a sphere keeps its
side of the frustum for at least the time the bound gives, whatever the camera and the sphere do
within their speed limits; over camera paths (walks, turns, a teleport, a change of fov) and
world changes (a set, a spawn, moving entities, a wrap-around) the rows drawn are exactly those
per-frame culling draws, while a still scene re-tests almost nothing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Mesh, ModelMatrix, Transform, Velocity
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.maths.camera import perspective, rotation_matrix, view_rotation, yaw_pitch_quat
from ecs_engine.maths.coherence import NEVER, coherence, crossing_times
from ecs_engine.maths.culling import bounding_spheres, frustum_planes, spheres_visible
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.culling.temporal_culling import SpeedLimits
from ecs_engine.render.extract.frame_data import FrameExtractor, check_culling


def test_crossing_times_solve_the_bound():
    t = crossing_times(np.array([1.0, 2.0, 0.0, 5.0]), np.array([2.0, 0.0, 1.0, 0.0]), np.array([0.0, 4.0, 1.0, 0.0]))
    assert t[0] == pytest.approx(0.5) and t[1] == pytest.approx(1.0) and t[2] == 0.0 and t[3] == NEVER
    margin, rate, accel = 3.0, 1.5, 0.7
    t = float(crossing_times(margin, rate, accel))
    assert rate * t + accel * t * t / 2 == pytest.approx(margin)


def test_no_sphere_changes_side_before_its_time_on_random_camera_paths():
    """Random frusta and spheres; the camera and the spheres then move and turn within their
    limits, either steadily (one axis, one heading: the worst case for a turn) or changing
    direction every step: at every step before a sphere's time its exact state is the one it had."""
    rng = np.random.default_rng(11)
    move, turn, frames, dt = 4.0, 1.2, 120, 1 / 60
    lens = perspective(math.radians(60), 1.5, 0.1, 200.0).astype(np.float64)
    checked = 0
    for trial in range(8):
        steady = trial % 2 == 0
        axis, heading_eye = rng.normal(size=3), rng.normal(size=3)
        n = 400
        centers = rng.uniform(-40, 40, (n, 3))
        radii = rng.uniform(0.1, 3.0, n)
        own = rng.uniform(0, 2.0, n) * (rng.random(n) < 0.5)
        eye = rng.uniform(-5, 5, 3)
        rotation = view_rotation(yaw_pitch_quat(rng.uniform(-3, 3), rng.uniform(-1, 1)))[:3, :3].astype(np.float64)
        planes = frustum_planes(lens, _view(rotation, eye))
        distances = centers @ planes[:, :3].T + planes[:, 3]
        offsets = np.abs(planes[:, :3] @ eye + planes[:, 3])
        visible, keep = coherence(distances, radii, np.linalg.norm(centers - eye, axis=1), offsets, move, turn, own)
        assert (visible == spheres_visible(centers, radii, planes)).all()
        assert (keep > 0).mean() > 0.5  # not a bound that says nothing
        for frame in range(1, frames + 1):
            axis = axis if steady else rng.normal(size=3)
            angle = turn * dt * (1.0 if steady else rng.uniform(0.5, 1.0))
            rotation = _axis_angle(axis / np.linalg.norm(axis), angle) @ rotation
            step = heading_eye if steady else rng.normal(size=3)
            eye = eye + step / np.linalg.norm(step) * move * dt * (1.0 if steady else rng.uniform(0.5, 1.0))
            heading = rng.normal(size=(n, 3))
            centers = centers + heading / np.linalg.norm(heading, axis=1)[:, None] * (own * dt)[:, None]
            now = spheres_visible(centers, radii, frustum_planes(lens, _view(rotation, eye)))
            young = keep > frame * dt
            assert (now[young] == visible[young]).all()
            checked += int(young.sum())
    assert checked > 50_000


def _view(rotation: np.ndarray, eye: np.ndarray) -> np.ndarray:
    view = np.eye(4)
    view[:3, :3] = rotation
    view[:3, 3] = -rotation @ eye
    return view


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


class Bounds:
    def __init__(self) -> None:
        mesh = cube_mesh()
        self.value = (np.array([mesh.center], np.float64), np.array([mesh.radius], np.float64), np.array([36]))


def world_with_rows(rng: np.random.Generator) -> tuple[World, int, np.ndarray]:
    world = World()
    still = world.spawn_batch(3_000, Transform(position=rng.uniform(-60, 60, (3_000, 3))), Mesh(handle=0))
    world.spawn_batch(
        500,
        Transform(position=rng.uniform(-60, 60, (500, 3))),
        Velocity(linear=rng.normal(scale=2.0, size=(500, 3))),
        Mesh(handle=0),
    )
    camera = add_camera(world, eye=(0.0, 0.0, 30.0), target=(0.0, 0.0, 0.0), move_speed=6.0)
    return world, camera, still


def exact_and_temporal(extractor: FrameExtractor, world: World, dt: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Per mesh row (chunk order): exact per-frame visibility, and what temporal culling draws."""
    data = extractor.extract(world, 16 / 9, 1, "temporal", dt=dt, bounds=Bounds().value)
    exact, drawn = [], []
    for chunk in data.chunks:
        centers, radii = bounding_spheres(chunk.model, *(b[chunk.handle] for b in Bounds().value[:2]))
        exact.append(spheres_visible(centers, radii, data.planes))
        drawn.append(data.visible(chunk))
    return np.concatenate(exact), np.concatenate(drawn)


@pytest.mark.parametrize("compiled", [True, False])
def test_temporal_culling_draws_what_exact_culling_draws_over_a_camera_path(compiled, monkeypatch):
    from ecs_engine.render.culling import temporal_kernels

    if compiled and temporal_kernels.moved_native is None:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    if not compiled:
        monkeypatch.setattr(temporal_kernels, "moved_native", None)
        monkeypatch.setattr(temporal_kernels, "retest_native", None)
    rng = np.random.default_rng(3)
    world, camera, still = world_with_rows(rng)
    schedule = default_schedule()
    extractor = FrameExtractor(lambda: 1)
    limits = SpeedLimits(6.0, math.sqrt(2.0) * 1.5)  # what the FlyCamera gives
    dt = 1 / 60
    tested = []

    def frame(step: float | None = dt) -> None:
        schedule.run(world, step or 0.0)
        exact, drawn = exact_and_temporal(extractor, world, step)
        assert (drawn >= exact).all(), "a row exact culling draws was culled"
        assert (drawn == exact).all()
        tested.append(extractor.temporal.stats.tested)

    for _ in range(3):
        frame()
    yaw = 0.0
    for _ in range(90):  # walk forward at the limit, turning at the limit
        cam = world.get(camera, Transform)
        yaw += limits.turn * dt * 0.99
        forward = rotation_matrix(cam.rotation)[:3, :3] @ np.array([0.0, 0.0, -1.0])
        world.set(
            camera,
            Transform,
            position=cam.position + forward * limits.move * dt * 0.99,
            rotation=yaw_pitch_quat(yaw, 0.0),
        )
        frame()
    assert max(tested[-80:]) < 3_500 / 2  # after the first frames only rows near an edge are tested
    world.set(camera, Transform, position=np.array([100.0, 0.0, 0.0]))  # a teleport
    frame()
    assert extractor.temporal.stats.everything
    for _ in range(5):  # still: the moving rows are checked, nothing else
        frame()
    assert tested[-1] < 200
    world.set(camera, Camera, fov_y=math.radians(90.0))  # the frustum's shape
    frame()
    assert extractor.temporal.stats.everything
    world.set(int(still[0]), Transform, position=np.array([100.0, 0.0, -20.0]))  # a set into view
    world.spawn_batch(10, Transform(position=np.tile([100.0, 0.0, -25.0], (10, 1))), Mesh(handle=0))
    frame()
    for batch in world.query(Velocity, Transform):  # a wrap-around: moved by a system, not by its Velocity
        batch[Transform].position[:50] *= -1
    frame()
    frame(None)  # no dt: a still camera keeps the rows' times


def test_min_interval_holds_rows_visible_longer_and_never_culls_a_drawn_row():
    rng = np.random.default_rng(4)
    world, camera, _ = world_with_rows(rng)
    schedule = default_schedule()
    extractor = FrameExtractor(lambda: 1)
    extractor.temporal.min_interval = 0.5
    dt, extra = 1 / 60, 0
    for k in range(60):
        world.set(camera, Transform, rotation=yaw_pitch_quat(k * 2.0 * dt, 0.0))
        schedule.run(world, dt)
        exact, drawn = exact_and_temporal(extractor, world, dt)
        assert (drawn >= exact).all()
        extra += int((drawn & ~exact).sum())
    assert extra > 0  # held rows: drawn though just outside


def test_the_culling_flag_is_checked():
    assert (
        check_culling(True) == "frustum" and check_culling(False) == "none" and check_culling("temporal") == "temporal"
    )
    from ecs_engine.errors import UsageError

    with pytest.raises(UsageError, match="unknown culling 'sideways'"):
        check_culling("sideways")
    with pytest.raises(UsageError, match="indirect mode culls on the GPU"):
        check_culling("temporal", "indirect")
    with pytest.raises(ValueError, match=r"SpeedLimits\.move"):
        SpeedLimits(float("nan"), 1.0)


def test_a_child_moved_by_its_parent_is_followed():
    """A child's own Transform never changes; its parent's does: its world place (WorldMatrix)
    is what the culler watches, not the ModelMatrix, which moves with the render origin."""
    from ecs_engine.components import Parent

    world = World()
    add_camera(world, eye=(0.0, 0.0, 10.0), target=(0.0, 0.0, 0.0))
    parent = world.spawn(Transform(position=(500.0, 0.0, 0.0)))
    child = world.spawn(Transform(position=(0.0, 1.0, 0.0)), Parent(entity=parent), Mesh(handle=0))
    world.spawn_batch(20, Transform(position=np.c_[np.arange(20.0), np.zeros((20, 2))]), Mesh(handle=0))
    schedule, extractor = default_schedule(), FrameExtractor(lambda: 1)
    for position in ((500.0, 0.0, 0.0), (500.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (-500.0, 0.0, 0.0)):
        world.set(parent, Transform, position=np.array(position))
        schedule.run(world, 1 / 60)
        exact, drawn = exact_and_temporal(extractor, world, 1 / 60)
        assert (drawn == exact).all()
    assert world.get(child, Mesh).handle == 0


def test_the_compiled_test_equals_the_numpy_one():
    from ecs_engine.render.culling import temporal_culling, temporal_kernels

    if temporal_kernels.retest_native is None:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    rng = np.random.default_rng(9)
    world = World()
    world.spawn_batch(
        2_000,
        Transform(position=rng.uniform(-50, 50, (2_000, 3)), scale=rng.uniform(0.2, 3, (2_000, 3))),
        Velocity(linear=rng.normal(size=(2_000, 3))),
        Mesh(handle=0),
    )
    add_camera(world, eye=(0.0, 0.0, 30.0), target=(0.0, 0.0, 0.0))
    default_schedule().run(world, 0.0)
    data = FrameExtractor(lambda: 1).extract(world, 1.5, 1, "frustum")
    batch = next(iter(world.query(ModelMatrix, Mesh, write=())))
    rows = rng.choice(2_000, 500, replace=False)
    eye = data.camera.position - data.origin
    offsets = np.abs(data.planes[:, :3] @ eye + data.planes[:, 3])
    args = (batch, rows, data.planes, eye, offsets, SpeedLimits(5.0, 1.0), Bounds().value)
    compiled = temporal_culling._retest_compiled(*args)
    reference = temporal_culling._retest_numpy(*args)
    for got, want in zip(compiled, reference):
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_a_still_camera_lowers_the_assumed_speeds_and_a_start_raises_them():
    from ecs_engine.render.culling.temporal_culling import CALM_FRAMES, RUNGS

    rng = np.random.default_rng(6)
    world, camera, _ = world_with_rows(rng)
    schedule, extractor = default_schedule(), FrameExtractor(lambda: 1)
    dt, tested = 1 / 60, []
    for _ in range(CALM_FRAMES * (len(RUNGS) + 1)):
        schedule.run(world, dt)
        exact, drawn = exact_and_temporal(extractor, world, dt)
        assert (drawn == exact).all()
        tested.append(extractor.temporal.stats.tested)
    assert extractor.temporal.assumed.rung == [0, 0]  # still: the lowest rung on both axes
    assert np.mean(tested[-CALM_FRAMES:]) < np.mean(tested[CALM_FRAMES : 2 * CALM_FRAMES])
    cam = world.get(camera, Transform)
    world.set(camera, Transform, position=cam.position + np.array([0.0, 0.0, -5.9 * dt]))  # at the limit
    schedule.run(world, dt)
    exact, drawn = exact_and_temporal(extractor, world, dt)
    assert (drawn == exact).all() and extractor.temporal.stats.everything
    assert extractor.temporal.assumed.rung[0] == len(RUNGS) - 1
