"""Frustum culling: a sphere just inside each plane is kept, just outside is dropped, and counts
match a brute-force reference built from the camera's geometry rather than its matrices."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine.maths.camera import perspective, rotation_matrix, view_rotation, yaw_pitch_quat
from ecs_engine.maths.culling import bounding_spheres, frustum_planes, spheres_visible

FOV, ASPECT, NEAR, FAR = math.radians(60.0), 16 / 9, 0.1, 50.0


def reference_planes(rotation: np.ndarray, far: float | None) -> np.ndarray:
    """Inward planes of the camera frustum from fov/aspect/near/far, rotated into the world."""
    ty = math.tan(FOV / 2)
    tx = ASPECT * ty
    local = [(1, 0, -tx, 0), (-1, 0, -tx, 0), (0, 1, -ty, 0), (0, -1, -ty, 0), (0, 0, -1, -NEAR)]
    if far is not None:
        local.append((0, 0, 1, far))
    r = rotation_matrix(rotation)[:3, :3]
    out = []
    for a, b, c, d in local:
        n = np.array([a, b, c], dtype=np.float64)
        scale = np.linalg.norm(n)
        out.append([*(r @ (n / scale)), d / scale])
    return np.array(out)


def brute_force(centers, radii, planes):
    keep = []
    for c, r in zip(centers, radii):
        keep.append(all(float(np.dot(p[:3], c) + p[3]) >= -r for p in planes))
    return np.array(keep)


@pytest.mark.parametrize("far", [FAR, math.inf])
def test_planes_match_the_camera_geometry(far):
    q = yaw_pitch_quat(0.7, -0.3)
    planes = frustum_planes(perspective(FOV, ASPECT, NEAR, far), view_rotation(q))
    ref = reference_planes(q, None if math.isinf(far) else far)
    assert planes.shape == ref.shape
    for p in ref:  # same set of planes (order may differ)
        assert np.abs(planes - p).max(axis=1).min() < 1e-5


@pytest.mark.parametrize("far", [FAR, math.inf])
def test_just_inside_and_just_outside_each_plane(far):
    q = yaw_pitch_quat(-1.1, 0.4)
    planes = frustum_planes(perspective(FOV, ASPECT, NEAR, far), view_rotation(q))
    r = rotation_matrix(q)[:3, :3]
    forward = r @ np.array([0.0, 0.0, -1.0])
    radius = 0.05
    for i, p in enumerate(planes):
        n, d = p[:3], p[3]
        # a point of this plane inside all the others: a point 5 units down the view axis,
        # projected onto the plane
        inner = forward * 5.0
        on_plane = inner - (np.dot(n, inner) + d) * n
        inside = on_plane + n * (radius * 0.5)  # centre inside: visible
        outside = on_plane - n * (radius * 1.5)  # whole sphere outside: culled
        centers = np.array([inside, outside])
        vis = spheres_visible(centers, np.array([radius, radius]), planes)
        assert vis.tolist() == [True, False], f"plane {i}"


def test_counts_match_brute_force_for_random_spheres():
    rng = np.random.default_rng(11)
    q = yaw_pitch_quat(0.3, 0.2)
    planes = frustum_planes(perspective(FOV, ASPECT, NEAR, FAR), view_rotation(q))
    ref = reference_planes(q, FAR)
    centers = rng.uniform(-60, 60, size=(5000, 3))
    radii = rng.uniform(0.0, 3.0, size=5000)
    fast = spheres_visible(centers, radii, planes)
    slow = brute_force(centers, radii, ref)
    assert 100 < fast.sum() < 4900  # a real mix
    # equal except for spheres within float rounding of a plane
    assert (fast != slow).sum() <= 2


def test_bounding_spheres_follow_the_model_matrix():
    model = np.zeros((2, 4, 4), dtype=np.float32)
    model[:, 3, 3] = 1
    model[0, :3, :3] = np.diag([2.0, 1.0, 0.5])
    model[0, :3, 3] = (1, 2, 3)
    model[1, :3, :3] = rotation_matrix(yaw_pitch_quat(0.5, 0.1))[:3, :3] * 3.0
    centers, radii = bounding_spheres(model, np.array([[0.5, 0.0, 0.0]] * 2), np.array([1.0, 1.0]))
    assert np.allclose(centers[0], [2.0, 2.0, 3.0])
    assert radii.tolist() == pytest.approx([2.0, 3.0], rel=1e-6)
