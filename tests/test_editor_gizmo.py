"""The gizmo's conversions (app/editor_gizmo.py): its OpenGL projection puts points on the same
pixels as the engine's reverse-Z one, and decompose undoes compose (mirrored too)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.app.editor_gizmo import column_major, from_column_major, gl_projection
from ecs_engine.components import ORTHOGRAPHIC, Camera, Transform
from ecs_engine.maths.decompose import decompose
from ecs_engine.maths.transform import compose_numpy
from ecs_engine.render.frame.camera import camera_matrices


@pytest.mark.parametrize("ortho", [False, True])
def test_the_gl_projection_lands_points_on_the_engines_pixels(ortho):
    world = World()
    camera = Camera(projection=ORTHOGRAPHIC, height=6.0, near=0.1, far=100.0) if ortho else Camera(near=0.1)
    world.spawn(Transform(), camera)
    engine = np.asarray(camera_matrices(world, 1.5).projection, np.float64)
    gl = gl_projection(world.get(world.query(Camera).entities()[0], Camera), 1.5)
    points = np.ones((50, 4))
    points[:, :3] = np.random.default_rng(0).uniform((-3, -2, -40), (3, 2, -1), (50, 3))
    a, b = points @ engine.T, points @ gl.T
    # the engine's Vulkan clip space has y down: the same pixel is -y in OpenGL's
    np.testing.assert_allclose(a[:, 0] / a[:, 3], b[:, 0] / b[:, 3], atol=1e-9)
    np.testing.assert_allclose(a[:, 1] / a[:, 3], -b[:, 1] / b[:, 3], atol=1e-9)


def test_decompose_undoes_compose_and_matrices_round_trip():
    rng = np.random.default_rng(1)
    for scale in ((1.0, 2.0, 0.5), (-1.5, 1.0, 3.0)):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        m = np.zeros((1, 4, 4))
        compose_numpy(np.array([[1.0, -2.0, 3.0]]), q[None], np.array([scale]), np.zeros(3), m)
        position, rotation, got_scale = decompose(m[0])
        again = np.zeros((1, 4, 4))
        compose_numpy(position[None], rotation[None], got_scale[None], np.zeros(3), again)
        np.testing.assert_allclose(again, m, atol=1e-12)
        assert math.isclose(np.linalg.norm(rotation), 1.0)
        np.testing.assert_allclose(from_column_major(np.array(column_major(m[0]))), m[0])
