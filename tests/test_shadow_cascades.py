"""Cascaded shadow maps' maths (maths/shadow_cascades.py): the splits, the slice's enclosing
sphere, the fitted light projection holding its slice, and stability: translating the camera
moves the map's texel grid by whole texels; turning it leaves the texel size alone."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine.maths.camera import orthographic, perspective
from ecs_engine.maths.shadow_cascades import (
    cascade_splits,
    fit_cascade,
    light_rotation,
    slice_sphere,
    view_slice_sphere,
)

FOV = math.radians(60.0)
TAN = math.tan(FOV / 2)
ASPECT = 16 / 9


def slice_corners(eye, forward, d0, d1):
    """The 8 corners of the perspective slice, built from a camera frame (independently of the
    sphere's formula)."""
    forward = np.asarray(forward, float) / np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    out = []
    for d in (d0, d1):
        for sx in (-1, 1):
            for sy in (-1, 1):
                out.append(eye + forward * d + right * (sx * TAN * ASPECT * d) + up * (sy * TAN * d))
    return np.array(out)


def fit(eye, forward, origin, d0, d1, light, res, reach=0.0):
    along, r = slice_sphere(d0, d1, TAN, ASPECT)
    return fit_cascade(
        np.asarray(eye, float) + along * np.asarray(forward, float), r, origin, light, res, reach, d0, d1
    )


def to_map(cascade, points_rel):
    """Render-relative points -> (x, y in [-1, 1], depth) through the cascade."""
    p = np.c_[points_rel, np.ones(len(points_rel))] @ cascade.view_projection.astype(np.float64).T
    return p[:, :3] / p[:, 3:]


def test_splits_run_from_near_to_far_between_uniform_and_logarithmic():
    uniform = cascade_splits(0.1, 100.0, 4, blend=0.0)
    log = cascade_splits(0.1, 100.0, 4, blend=1.0)
    mixed = cascade_splits(0.1, 100.0, 4)
    np.testing.assert_allclose(uniform, np.linspace(0.1, 100.0, 5))
    np.testing.assert_allclose(log[1:] / log[:-1], (1000.0) ** 0.25)
    assert mixed[0] == 0.1 and mixed[-1] == 100.0 and (np.diff(mixed) > 0).all()
    assert (log[1:-1] < mixed[1:-1]).all() and (mixed[1:-1] < uniform[1:-1]).all()
    for bad in (dict(count=0), dict(count=5), dict(blend=1.5)):
        with pytest.raises(ValueError):
            cascade_splits(0.1, 100.0, **{"count": 4, **bad})
    with pytest.raises(ValueError, match="shadow distance"):
        cascade_splits(1.0, math.inf, 4)


def test_the_sphere_of_a_cameras_slice_follows_its_projection():
    along, r = view_slice_sphere(perspective(FOV, ASPECT, 0.1), 2.0, 9.0)
    assert (along, r) == pytest.approx(slice_sphere(2.0, 9.0, TAN, ASPECT))
    along, r = view_slice_sphere(orthographic(6.0, 2.0, 0.1, 100.0), 2.0, 10.0)
    assert along == pytest.approx(6.0) and r == pytest.approx(math.sqrt(6.0**2 + 3.0**2 + 4.0**2))


@pytest.mark.parametrize(("d0", "d1"), [(0.1, 5.0), (5.0, 20.0), (20.0, 21.0), (0.1, 200.0)])
def test_the_slice_sphere_holds_the_slice_and_touches_it(d0, d1):
    along, r = slice_sphere(d0, d1, TAN, ASPECT)
    corners = slice_corners(np.zeros(3), [0.0, 0.0, -1.0], d0, d1)
    dist = np.linalg.norm(corners - np.array([0.0, 0.0, -along]), axis=1)
    assert dist.max() <= r * (1 + 1e-12)
    assert dist.max() >= r * (1 - 1e-9)  # the smallest such sphere: a corner lies on it


def test_a_cascade_holds_its_slice_and_casters_towards_the_light():
    rng = np.random.default_rng(4)
    for _ in range(20):
        eye = rng.uniform(-5, 5, 3)
        forward = rng.normal(size=3)
        forward /= np.linalg.norm(forward)
        light = rng.normal(size=3)
        origin = rng.uniform(-1e5, 1e5, 3)
        c = fit(eye, forward, origin, 2.0, 15.0, light, 1024, reach=30.0)
        m = to_map(c, slice_corners(eye, forward, 2.0, 15.0))
        assert (np.abs(m[:, :2]) <= 1 + 1e-4).all() and (m[:, 2] >= -1e-4).all() and (m[:, 2] <= 1 + 1e-4).all()
        # a caster 25 units towards the light from the slice's middle still lands in the map
        middle = eye + forward * 8.5 - 25.0 * light / np.linalg.norm(light)
        assert 0.0 <= to_map(c, middle[None])[0, 2] <= 1.0


def test_translating_the_camera_moves_the_texel_grid_by_whole_texels():
    """A fixed world point's texel coordinate keeps its fraction: a static shadow edge stays put
    (no shimmering), wherever the camera and the render origin (the camera) go."""
    rng = np.random.default_rng(7)
    light = np.array([0.3, -1.0, -0.4])
    forward = np.array([0.0, -0.3, -1.0])
    forward /= np.linalg.norm(forward)
    points = rng.uniform(-3, 3, (50, 3)) + np.array([0.0, 0.0, -8.0])  # world, near the slice
    res = 2048
    fractions = []
    for step in range(8):
        camera = np.array([0.0, 2.0, 0.0]) + step * np.array([0.0123, 0.0041, -0.0377])  # sub-texel steps
        c = fit(np.zeros(3), forward, camera, 1.0, 20.0, light, res)
        uv = (to_map(c, points - camera)[:, :2] * 0.5 + 0.5) * res
        fractions.append(uv - np.floor(uv))
        assert c.texel == pytest.approx(2 * c.radius / res)
    f = np.array(fractions)
    drift = np.abs((f - f[0] + 0.5) % 1.0 - 0.5)  # distance on the circle of fractions
    assert drift.max() < 2e-3, drift.max()
    # without snapping the fractions would wander by ~the step / texel: the test can fail
    assert np.abs(np.diff(np.array([0.0123, 0.0041]))).max() / (2 * c.radius / res) > 0.05


def test_turning_the_camera_keeps_the_texel_size():
    light = np.array([0.2, -1.0, 0.1])
    sizes = set()
    for yaw in np.linspace(0, 2 * math.pi, 9):
        forward = np.array([math.sin(yaw), -0.2, -math.cos(yaw)])
        forward /= np.linalg.norm(forward)
        c = fit(np.zeros(3), forward, np.zeros(3), 3.0, 30.0, light, 1024)
        sizes.add(round(c.texel, 12))
    assert len(sizes) == 1


@pytest.mark.parametrize("direction", [(0.0, -1.0, 0.0), (0.0, 1.0, 0.0), (1e-4, -1.0, 0.0), (1.0, 0.0, 0.0)])
def test_the_light_frame_is_orthonormal_even_straight_down(direction):
    rot = light_rotation(np.array(direction))
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(rot[2], -np.array(direction) / np.linalg.norm(direction), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="light direction"):
        light_rotation(np.zeros(3))
