"""Reverse-Z projections (NDC and depth of known points, y flip, float32 depth ordering), the
rotation-only view, yaw/pitch quaternions and the active-camera lookup."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import ActiveCamera
from ecs_engine.components.camera import ORTHOGRAPHIC, Camera
from ecs_engine.components.transform import Transform
from ecs_engine.errors import UsageError
from ecs_engine.maths.camera import orthographic, perspective, view_rotation, yaw_pitch_quat
from ecs_engine.maths.transform import quat_to_mat3
from ecs_engine.render.frame.camera import camera_matrices

FOV = math.radians(60.0)


def project(m: np.ndarray, points: np.ndarray) -> np.ndarray:
    """View-space points (n, 3) -> NDC (n, 3), in float64 from the float32 matrix."""
    p = np.c_[np.asarray(points, dtype=np.float64), np.ones(len(points))]
    clip = p @ m.astype(np.float64).T
    return clip[:, :3] / clip[:, 3:]


def project_f32(m: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The same, every step in float32 as the GPU does it."""
    p = np.c_[np.asarray(points, dtype=np.float32), np.ones(len(points), dtype=np.float32)]
    clip = (p @ m.T).astype(np.float32)
    return clip[:, :3] / clip[:, 3:]


def on_axis(distances) -> np.ndarray:
    d = np.asarray(distances, dtype=np.float64)
    return np.stack([np.zeros_like(d), np.zeros_like(d), -d], axis=1)


def forward_z_perspective(fov_y, aspect, near, far):
    """Conventional (not reversed) depth, near -> 0, far -> 1: the control for the precision test."""
    m = perspective(fov_y, aspect, near, far).astype(np.float64)
    m[2, 2] = -far / (far - near)
    m[2, 3] = -far * near / (far - near)
    return m.astype(np.float32)


# --------------------------------------------------------------------------- perspective
@pytest.mark.parametrize("far", [100.0, math.inf])
def test_perspective_near_plane_maps_to_depth_one(far):
    m = perspective(FOV, 1.5, 0.1, far)
    assert m.dtype == np.float32 and m.shape == (4, 4)
    assert project(m, on_axis([0.1]))[0, 2] == pytest.approx(1.0, abs=1e-6)


def test_finite_far_plane_maps_to_depth_zero():
    m = perspective(FOV, 1.5, 0.1, 100.0)
    depth = project(m, on_axis([0.1, 1.0, 10.0, 100.0]))[:, 2]
    assert depth[-1] == pytest.approx(0.0, abs=1e-6)
    n, f = 0.1, 100.0
    expected = n * (f - np.array([0.1, 1.0, 10.0, 100.0])) / ((f - n) * np.array([0.1, 1.0, 10.0, 100.0]))
    assert np.allclose(depth, expected, rtol=1e-6, atol=1e-7)


def test_infinite_far_depth_is_near_over_distance_and_tends_to_zero():
    near = 0.05
    m = perspective(FOV, 1.0, near, math.inf)
    d = np.array([0.05, 0.1, 1.0, 7.5, 1e3, 1e6, 1e12, 1e30])
    depth = project(m, on_axis(d))[:, 2]
    assert np.allclose(depth, near / d, rtol=1e-6, atol=0.0)
    assert depth[-1] < 1e-30 and depth[-1] >= 0.0


def test_frustum_edges_and_y_flip():
    aspect, d = 1.6, 7.0
    m = perspective(FOV, aspect, 0.1)
    t = math.tan(FOV / 2) * d
    ndc = project(m, np.array([[0.0, t, -d], [0.0, -t, -d], [t * aspect, 0.0, -d], [-t * aspect, 0.0, -d]]))
    # Vulkan NDC y points down: world up (+Y) lands at the top of the screen, y = -1
    assert np.allclose(ndc[:, :2], [[0, -1], [0, 1], [1, 0], [-1, 0]], atol=1e-6)


def test_nearer_points_get_greater_depth():
    for far in (50.0, math.inf):
        m = perspective(FOV, 1.0, 0.1, far)
        depth = project(m, on_axis(np.linspace(0.1, 50.0, 200)))[:, 2]
        assert (np.diff(depth) < 0).all()
        assert ((depth >= -1e-7) & (depth <= 1 + 1e-6)).all()  # float32 matrix rounding


def test_points_behind_the_camera_or_before_near_fall_outside_0_1():
    m = perspective(FOV, 1.0, 0.1, 100.0)
    assert project(m, on_axis([0.05]))[0, 2] > 1.0  # closer than near: clipped
    assert project(m, on_axis([200.0]))[0, 2] < 0.0  # beyond far: clipped
    clip = m.astype(np.float64) @ np.array([0.0, 0.0, 1.0, 1.0])  # behind the camera
    assert clip[3] < 0.0


PRECISION_DISTANCES = [0.02, 0.1, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5]


@pytest.mark.parametrize("far", [1e6, math.inf])
@pytest.mark.parametrize("pipeline", ["float64_rounded", "float32"])
def test_float32_depth_keeps_order_of_points_1e4_relative_apart(far, pipeline):
    m = perspective(FOV, 1.0, 0.01, far)
    d = np.array(PRECISION_DISTANCES)
    if pipeline == "float64_rounded":
        near_pts = project(m, on_axis(d))[:, 2].astype(np.float32)
        far_pts = project(m, on_axis(d * (1 + 1e-4)))[:, 2].astype(np.float32)
    else:
        near_pts = project_f32(m, on_axis(d))[:, 2]
        far_pts = project_f32(m, on_axis(d * (1 + 1e-4)))[:, 2]
    assert near_pts.dtype == np.float32
    assert (near_pts > far_pts).all(), list(zip(d, near_pts, far_pts))


def test_the_precision_test_fails_for_conventional_depth():
    """Control: with near -> 0, far -> 1 the same points collide in float32 far away."""
    m = forward_z_perspective(FOV, 1.0, 0.01, 1e6)
    d = np.array([1e4, 1e5])
    a = project(m, on_axis(d))[:, 2].astype(np.float32)
    b = project(m, on_axis(d * (1 + 1e-4)))[:, 2].astype(np.float32)
    assert (a == b).any()


@pytest.mark.parametrize(
    "args",
    [
        (0.0, 1.0, 0.1, 10.0),
        (math.pi, 1.0, 0.1, 10.0),
        (FOV, 0.0, 0.1, 10.0),
        (FOV, 1.0, 0.0, 10.0),
        (FOV, 1.0, 1.0, 1.0),
        (FOV, 1.0, 0.1, math.nan),
        (FOV, math.inf, 0.1, 10.0),
    ],
)
def test_perspective_rejects_bad_parameters(args):
    with pytest.raises(ValueError):
        perspective(*args)


# ------------------------------------------------------------------------- orthographic
def test_orthographic_maps_box_to_ndc_with_reverse_depth():
    height, aspect, near, far = 8.0, 2.0, 0.5, 20.0
    m = orthographic(height, aspect, near, far)
    assert m.dtype == np.float32
    pts = np.array([[8.0, 4.0, -0.5], [-8.0, -4.0, -20.0], [0.0, 0.0, -10.25]])
    ndc = project(m, pts)
    assert np.allclose(ndc, [[1, -1, 1], [-1, 1, 0], [0, 0, 0.5]], atol=1e-6)
    depth = project(m, on_axis(np.linspace(near, far, 50)))[:, 2]
    assert (np.diff(depth) < 0).all()


def test_orthographic_needs_finite_far():
    with pytest.raises(ValueError):
        orthographic(1.0, 1.0, 0.1, math.inf)
    with pytest.raises(ValueError):
        orthographic(1.0, 1.0, 2.0, 1.0)


# ----------------------------------------------------------------------- view rotation
def test_yaw_pitch_quat_directions():
    def forward(yaw, pitch):
        return quat_to_mat3(yaw_pitch_quat(yaw, pitch)[None])[0] @ np.array([0.0, 0.0, -1.0])

    assert np.allclose(forward(0.0, 0.0), [0, 0, -1])
    assert np.allclose(forward(math.pi / 2, 0.0), [-1, 0, 0])  # positive yaw turns left (CCW from above)
    assert np.allclose(forward(-math.pi / 2, 0.0), [1, 0, 0])
    assert np.allclose(forward(0.0, 0.3), [0, math.sin(0.3), -math.cos(0.3)])  # positive pitch looks up
    yaw, pitch = 0.7, -0.4
    expected = [-math.sin(yaw) * math.cos(pitch), math.sin(pitch), -math.cos(yaw) * math.cos(pitch)]
    assert np.allclose(forward(yaw, pitch), expected)
    right = quat_to_mat3(yaw_pitch_quat(yaw, pitch)[None])[0] @ np.array([1.0, 0.0, 0.0])
    assert right[1] == pytest.approx(0.0, abs=1e-15)  # no roll: the right vector stays level


def test_yaw_pitch_quat_is_yaw_times_local_pitch_and_vectorises():
    yaw, pitch = np.array([0.3, -2.0, 3.1]), np.array([0.2, 1.2, -1.5])
    q = yaw_pitch_quat(yaw, pitch)
    assert q.shape == (3, 4) and q.dtype == np.float64
    ry = quat_to_mat3(np.stack([0 * yaw, np.sin(yaw / 2), 0 * yaw, np.cos(yaw / 2)], axis=1))
    rx = quat_to_mat3(np.stack([np.sin(pitch / 2), 0 * pitch, 0 * pitch, np.cos(pitch / 2)], axis=1))
    assert np.allclose(quat_to_mat3(q), ry @ rx, atol=1e-14)
    assert np.allclose(yaw_pitch_quat(0.3, 0.2), q[0], atol=0)
    assert yaw_pitch_quat(0.0, 0.0).tolist() == [0.0, 0.0, 0.0, 1.0]


def test_view_rotation_is_inverse_rotation_without_translation():
    q = yaw_pitch_quat(1.1, -0.6)
    v = view_rotation(q)
    assert v.dtype == np.float32
    assert np.allclose(v[:3, 3], 0) and np.allclose(v[3], [0, 0, 0, 1])
    world_from_cam = quat_to_mat3(q[None])[0]
    assert np.allclose(v[:3, :3].astype(np.float64) @ world_from_cam, np.eye(3), atol=1e-6)
    # the camera's own forward comes out as -Z in view space
    assert np.allclose(v[:3, :3] @ (world_from_cam @ [0.0, 0.0, -1.0]), [0, 0, -1], atol=1e-6)
    # non-unit quaternions are normalised
    assert np.allclose(view_rotation(q * 3.0), v, atol=1e-7)
    with pytest.raises(ValueError):
        view_rotation(np.zeros(4))


# ---------------------------------------------------------------------- active camera
def test_camera_matrices_single_camera_uses_viewport_aspect_and_float64_position():
    w = World()
    pos = np.array([1e7 + 0.125, -3.0, 2e6 + 0.5])
    q = yaw_pitch_quat(0.5, 0.1)
    e = w.spawn(Camera(fov_y=FOV, near=0.2), Transform(position=pos, rotation=q))
    cm = camera_matrices(w, 2.0)
    assert cm.entity == e
    assert cm.position.dtype == np.float64 and cm.position.tolist() == pos.tolist()
    assert np.array_equal(cm.projection, perspective(FOV, 2.0, 0.2))
    assert np.array_equal(cm.view, view_rotation(q))
    assert np.allclose(cm.view @ cm.inverse_view, np.eye(4), atol=1e-6)
    assert cm.near == 0.2 and cm.far == math.inf
    for a in (cm.projection, cm.view, cm.inverse_view):
        assert a.dtype == np.float32 and a.shape == (4, 4)
    # a world point straight ahead of the camera projects to the screen centre at depth near/d
    ahead = pos + 40.0 * (quat_to_mat3(q[None])[0] @ [0.0, 0.0, -1.0])
    rel = (ahead - cm.position).astype(np.float32)  # camera-relative, then float32
    clip = cm.projection @ cm.view @ np.r_[rel, 1.0].astype(np.float32)
    ndc = clip[:3] / clip[3]
    assert np.allclose(ndc, [0, 0, 0.2 / 40.0], atol=1e-6)


def test_camera_aspect_overrides_viewport_and_orthographic_is_built():
    w = World()
    w.spawn(Camera(projection=ORTHOGRAPHIC, height=6.0, near=0.5, far=50.0, aspect=1.25), Transform())
    cm = camera_matrices(w, 16 / 9)
    assert np.array_equal(cm.projection, orthographic(6.0, 1.25, 0.5, 50.0))


def test_orthographic_camera_with_infinite_far_is_a_usage_error():
    w = World()
    w.spawn(Camera(projection=ORTHOGRAPHIC), Transform())
    with pytest.raises(UsageError, match="far"):
        camera_matrices(w, 1.0)


def test_active_camera_selection_rules():
    w = World()
    with pytest.raises(UsageError, match="no camera"):
        camera_matrices(w, 1.0)
    w.spawn(Transform())  # not a camera
    a = w.spawn(Camera(near=0.1), Transform())
    assert camera_matrices(w, 1.0).entity == a  # the only one: no tag needed
    b = w.spawn(Camera(near=0.3), Transform())
    with pytest.raises(UsageError, match="ActiveCamera"):
        camera_matrices(w, 1.0)
    w.add(b, ActiveCamera())
    cm = camera_matrices(w, 1.0)
    assert cm.entity == b and cm.near == 0.3
    w.add(a, ActiveCamera())
    with pytest.raises(UsageError, match="2 cameras are tagged"):
        camera_matrices(w, 1.0)
    w.remove(b, ActiveCamera)
    assert camera_matrices(w, 1.0).entity == a


def test_camera_matrices_rejects_bad_viewport_aspect():
    w = World()
    w.spawn(Camera(), Transform())
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError):
            camera_matrices(w, bad)


def test_camera_matrices_are_kept_while_the_camera_is_still_and_remade_when_it_changes():
    w = World()
    e = w.spawn(Camera(fov_y=FOV), Transform(position=(1.0, 2.0, 3.0)))
    w.spawn(Transform(position=(5.0, 0.0, 0.0)))  # another table: its writes do not matter
    first = camera_matrices(w, 1.5)
    assert camera_matrices(w, 1.5) is first  # nothing changed: the same object
    assert not first.projection.flags.writeable and not first.position.flags.writeable
    assert camera_matrices(w, 2.0).projection[0, 0] != first.projection[0, 0]  # the viewport
    w.set(e, Transform, position=(4.0, 5.0, 6.0))
    moved = camera_matrices(w, 1.5)
    assert moved.position.tolist() == [4.0, 5.0, 6.0]
    q = yaw_pitch_quat(0.3, 0.0)
    w.set(e, Transform, rotation=q)
    assert np.array_equal(camera_matrices(w, 1.5).view, view_rotation(q))
    w.set(e, Camera, fov_y=FOV / 2)
    assert np.array_equal(camera_matrices(w, 1.5).projection, perspective(FOV / 2, 1.5, 0.1))
    other = w.spawn(Camera(near=0.5), Transform(), ActiveCamera())  # structure changed
    assert camera_matrices(w, 1.5).entity == other
    w.destroy(other)
    assert camera_matrices(w, 1.5).entity == e


@pytest.mark.parametrize("lens", [perspective(1.0, 1.6, 0.1), orthographic(4.0, 1.6, 0.1, 50.0)])
def test_a_region_projection_shows_the_lens_view_inside_the_region(lens):
    """Every point lands in the region where the lens puts it in a whole target; depth is kept."""
    from ecs_engine.maths.camera import region_projection

    region = (0.25, 0.1, 0.75, 0.6)
    full = region_projection(lens, region).astype(np.float64)
    points = np.c_[np.random.default_rng(3).uniform(-2, 2, (50, 2)), -np.linspace(1, 20, 50), np.ones(50)]
    a, b = points @ lens.astype(np.float64).T, points @ full.T
    a, b = a[:, :3] / a[:, 3:], b[:, :3] / b[:, 3:]
    fx, fy = (a[:, 0] + 1) / 2, (a[:, 1] + 1) / 2  # fractions of the region
    np.testing.assert_allclose((b[:, 0] + 1) / 2, region[0] + fx * (region[2] - region[0]), atol=1e-5)
    np.testing.assert_allclose((b[:, 1] + 1) / 2, region[1] + fy * (region[3] - region[1]), atol=1e-5)
    np.testing.assert_allclose(b[:, 2], a[:, 2], rtol=1e-5)
    for bad in [(0.5, 0.1, 0.5, 0.6), (-0.1, 0, 1, 1), (0, 0, 1, 1.5), (0.6, 0, 0.4, 1)]:
        with pytest.raises(ValueError, match="a region is"):
            region_projection(lens, bad)
