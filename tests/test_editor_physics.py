"""The editor's Physics window (app/editor_physics.py): the colliders' wireframes are their
shapes' edges where the camera sees them; with a physics world the window pauses and steps the
bodies and draws the wireframes over the Scene window."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.app.editor_gizmo import gl_projection
from ecs_engine.app.editor_physics import ROUND, collider_segments, project
from ecs_engine.components import Camera, Transform
from ecs_engine.components.physics import BOX, CAPSULE, SPHERE


def test_a_box_wireframe_is_its_twelve_edges_where_the_body_stands():
    q = np.array([0.0, math.sin(math.pi / 8), 0.0, math.cos(math.pi / 8)])  # 45 degrees about y
    segments = collider_segments(np.array([[1.0, 2.0, 3.0]]), q[None], np.array([BOX]), np.array([[1.0, 0.5, 0.25]]))
    assert segments.shape == (12, 2, 3)
    lengths = np.sort(np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1))
    np.testing.assert_allclose(lengths, [0.5] * 4 + [1.0] * 4 + [2.0] * 4)  # twice each half extent
    np.testing.assert_allclose(segments.reshape(-1, 3).mean(axis=0), (1.0, 2.0, 3.0), atol=1e-12)
    assert np.abs(segments.reshape(-1, 3)[:, 1] - 2.0).max() == pytest.approx(0.5)  # y untouched by the turn


def test_round_wireframes_lie_on_their_surfaces():
    spheres = collider_segments(
        np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]), np.array([SPHERE]), np.full((1, 3), 2.0)
    )
    assert spheres.shape == (3 * ROUND, 2, 3)
    np.testing.assert_allclose(np.linalg.norm(spheres.reshape(-1, 3), axis=1), 2.0)
    capsule = collider_segments(
        np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]), np.array([CAPSULE]), np.array([[0.5, 1.0, 0.5]])
    )
    assert capsule.shape == (2 * ROUND + 4, 2, 3)
    points = capsule.reshape(-1, 3)
    np.testing.assert_allclose(np.hypot(points[:, 0], points[:, 2]), 0.5)  # on the cylinder
    assert set(np.round(points[:, 1], 9)) == {-1.0, 1.0}


def test_projection_puts_the_point_ahead_in_the_middle_and_leaves_out_what_is_behind():
    world = World()
    world.spawn(Transform(), Camera(near=0.1))
    camera = world.get(world.query(Camera).entities()[0], Camera)
    proj = gl_projection(camera, 2.0)
    rect = (100.0, 50.0, 500.0, 250.0)
    points = np.array([[0.0, 0.0, -5.0], [0.0, 0.0, 5.0], [1.0, 0.0, -5.0]])
    screen, front = project(points, np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]), proj, rect)
    np.testing.assert_allclose(screen[0], (300.0, 150.0))
    assert list(front) == [True, False, True] and screen[2, 0] > 300.0  # +x is to the right


def test_the_physics_window_pauses_steps_and_draws_colliders():
    pytest.importorskip("culverin", reason="the physics extra (CPython 3.12+): make test-physics")
    from imgui_bundle import imgui
    from test_editor import Scene

    from ecs_engine.components.physics import Collider, RigidBody
    from ecs_engine.physics import PhysicsWorld

    scene = Scene("cube")
    try:
        world, editor = scene.state.world, scene.session.editor
        physics = world.resources[PhysicsWorld] = PhysicsWorld(threads=1)
        cube = int(world.query(Transform).entities()[0])
        world.add(cube, RigidBody())
        world.add(cube, Collider(shape=BOX))
        for _ in range(3):
            scene.frame()
        assert imgui.internal.find_window_by_name("Physics") is not None
        window = imgui.internal.find_window_by_name("Scene")
        bare = window.draw_list.vtx_buffer.size()
        editor.physics.show_colliders = True
        scene.frame()
        scene.frame()
        window = imgui.internal.find_window_by_name("Scene")
        assert window.draw_list.vtx_buffer.size() >= bare + 12 * 4  # twelve edges, a quad each
        physics.paused = True
        assert not physics.step_once
    finally:
        scene.close()
