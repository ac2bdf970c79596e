"""Matrix composition and motion integration: native kernels against the NumPy reference and
against independent constructions; degenerate scales stay finite."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import native
from ecs_engine.maths import transform as tm

rng = np.random.default_rng(7)


def random_inputs(n):
    pos = rng.normal(scale=1e3, size=(n, 3))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    scale = rng.uniform(0.1, 5.0, size=(n, 3)) * rng.choice([-1.0, 1.0], size=(n, 3))
    return pos, q, scale


def axis_angle_matrix(axis, angle):
    """Rodrigues' formula: an independent rotation construction."""
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def compose_both(pos, q, scale, origin):
    n = len(pos)
    out = []
    for fn in (tm.compose, tm.compose_numpy):
        model = np.full((n, 4, 4), np.nan, dtype=np.float32)
        normal = np.full((n, 3, 3), np.nan, dtype=np.float32)
        fn(pos, q, scale, origin, model, normal)
        out.append((model, normal))
        alone = np.full((n, 4, 4), np.nan, dtype=np.float32)
        fn(pos, q, scale, origin, alone)  # no normal matrices asked for: the same model matrices
        assert np.array_equal(alone, model)
    return out


def test_quaternion_matrix_matches_axis_angle():
    axis = np.array([1.0, 2.0, -0.5])
    angle = 1.1
    a = axis / np.linalg.norm(axis)
    q = np.array([[*(a * np.sin(angle / 2)), np.cos(angle / 2)]])
    assert np.allclose(tm.quat_to_mat3(q)[0], axis_angle_matrix(axis, angle))


def test_native_and_numpy_agree_and_write_every_element():
    pos, q, scale = random_inputs(1000)
    origin = np.array([10.0, -20.0, 30.0])
    (m1, n1), (m2, n2) = compose_both(pos, q, scale, origin)
    assert np.isfinite(m1).all() and np.isfinite(n1).all()
    assert np.allclose(m1, m2, rtol=1e-6, atol=1e-4)
    assert np.allclose(n1, n2, rtol=1e-6, atol=1e-6)


def test_model_matrix_is_trs_relative_to_origin():
    pos, q, scale = random_inputs(50)
    origin = np.array([1e6, 0.0, -1e6])
    pos = pos + origin
    (model, _), _ = compose_both(pos, q, scale, origin)
    for i in range(50):
        expected = np.eye(4)
        expected[:3, :3] = tm.quat_to_mat3(q[i : i + 1])[0] @ np.diag(scale[i])
        expected[:3, 3] = pos[i] - origin
        assert np.allclose(model[i], expected, rtol=1e-5, atol=1e-3)


def test_camera_relative_translation_keeps_precision_far_from_origin():
    """1e7 away, 1 mm apart: float32 of the absolute position would lose the millimetre."""
    base = 1e7
    pos = np.array([[base + 0.001, 0.0, 0.0], [base + 0.002, 0.0, 0.0]])
    q = np.array([[0, 0, 0, 1.0]] * 2)
    s = np.ones((2, 3))
    (model, _), _ = compose_both(pos, q, s, np.array([base, 0.0, 0.0]))
    assert model[1, 0, 3] - model[0, 0, 3] == pytest.approx(0.001, rel=1e-4)
    assert np.float32(base + 0.002) - np.float32(base + 0.001) == 0.0  # what we avoid


def test_normal_matrix_transforms_normals_like_inverse_transpose():
    pos, q, scale = random_inputs(200)
    (model, normal), _ = compose_both(pos, q, scale, np.zeros(3))
    for i in range(200):
        m3 = model[i, :3, :3].astype(np.float64)
        ref = np.linalg.inv(m3).T
        for nvec in np.eye(3):
            a = normal[i] @ nvec
            b = ref @ nvec
            a /= np.linalg.norm(a)
            b /= np.linalg.norm(b)
            assert np.allclose(a, b, atol=1e-4)  # same direction, same (outward) sign


@pytest.mark.parametrize(
    "scale",
    [
        (0.0, 1.0, 1.0),
        (0.0, 0.0, 1.0),
        (0.0, 0.0, 0.0),
        (-1.0, 1.0, 1.0),
        (-2.0, -3.0, -4.0),
        (1e30, 1e30, 1e30),
        (1e-30, 1e-30, 1e-30),
    ],
)
def test_degenerate_scales_give_finite_bounded_normals(scale):
    pos = np.zeros((1, 3))
    q = np.array([[0.1, 0.2, 0.3, 0.9]])
    q /= np.linalg.norm(q)
    s = np.array([scale], dtype=np.float64)
    (_, n1), (_, n2) = compose_both(pos, q, s, np.zeros(3))
    for normal in (n1, n2):
        assert np.isfinite(normal).all()
        assert np.abs(normal).max() <= 1.0 + 1e-6
    assert np.allclose(n1, n2, atol=1e-6)
    if scale == (0.0, 1.0, 1.0):
        # flattened along x: only the x column survives, the face normal of the flat object
        r = tm.quat_to_mat3(q)[0]
        assert np.allclose(n1[0][:, 0], r[:, 0], atol=1e-6)
        assert np.allclose(n1[0][:, 1:], 0.0)


def test_mirrored_scale_keeps_normals_outward():
    """A mirror in x: the +x face of a unit cube ends at -x and must face -x."""
    pos = np.zeros((1, 3))
    q = np.array([[0.0, 0.0, 0.0, 1.0]])
    s = np.array([[-1.0, 1.0, 1.0]])
    (_, normal), _ = compose_both(pos, q, s, np.zeros(3))
    assert np.allclose(normal[0] @ [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0])


def test_unnormalised_quaternion_is_treated_as_its_unit():
    q = np.array([[0.0, 0.0, 3.0, 3.0]])
    r = tm.quat_to_mat3(q)[0]
    assert np.allclose(r, axis_angle_matrix(np.array([0, 0, 1.0]), np.pi / 2))


def test_angular_integration_is_exact_for_constant_rate_and_paths_agree():
    n = 500
    rot = rng.normal(size=(n, 4))
    rot /= np.linalg.norm(rot, axis=1, keepdims=True)
    ang = rng.normal(size=(n, 3)) * 3
    ang[0] = 0.0  # zero rate: unchanged
    ang[1] = [0, 0, 1e-14]  # tiny rate: no division trouble
    a, b = rot.copy(), rot.copy()
    tm.integrate_angular(a, ang, 0.25)
    tm.integrate_angular_numpy(b, ang, 0.25)
    assert np.allclose(a, b, atol=1e-12)
    assert np.allclose(a[0], rot[0])
    for i in (2, 3, 4):
        rate = np.linalg.norm(ang[i])
        dq = axis_angle_matrix(ang[i], rate * 0.25)
        expected = dq @ tm.quat_to_mat3(rot[i : i + 1])[0]
        assert np.allclose(tm.quat_to_mat3(a[i : i + 1])[0], expected, atol=1e-12)
    assert np.allclose(np.linalg.norm(a, axis=1), 1.0)


def test_motion_integrates_strided_views_in_place():
    """The native kernels take flat contiguous arrays; a strided view must still be updated in
    place (through the NumPy path), never a silent copy."""
    rot = rng.normal(size=(40, 4))
    pos = rng.normal(size=(40, 3))
    ang = rng.normal(size=(20, 3))
    expected_rot, expected_pos = rot.copy(), pos.copy()
    tm.integrate_angular_numpy(expected_rot[::2], ang, 0.1)
    tm.integrate_linear_numpy(expected_pos[::2], ang, 0.1)
    tm.integrate_angular(rot[::2], ang, 0.1)
    tm.integrate_linear(pos[::2], ang, 0.1)
    assert np.allclose(rot, expected_rot, atol=1e-14) and np.array_equal(rot[1::2], expected_rot[1::2])
    assert np.allclose(pos, expected_pos, atol=1e-14)


def test_angular_rows_of_both_paths_in_one_array_agree_with_reference():
    """Slow and fast rates mixed row by row: the vectorised pass leaves the fast rows for the
    sin/cos pass, which must find each of them (and leave the others alone)."""
    n = 1000
    rot = rng.normal(size=(n, 4))
    ang = rng.normal(size=(n, 3)) * np.where(rng.random((n, 1)) < 0.3, 500.0, 1.0)
    a, b = rot.copy(), rot.copy()
    tm.integrate_angular(a, ang, 1 / 60)
    tm.integrate_angular_numpy(b, ang, 1 / 60)
    assert np.allclose(a, b, atol=1e-13)


def test_many_small_rotation_steps_do_not_drift_off_unit_length():
    rot = np.array([[0.0, 0.0, 0.0, 1.0]])
    ang = np.array([[0.3, -1.2, 0.7]])
    for _ in range(10_000):
        tm.integrate_angular(rot, ang, 1e-3)
    assert abs(np.linalg.norm(rot) - 1.0) < 1e-12
    rate = np.linalg.norm(ang[0])
    expected = axis_angle_matrix(ang[0], rate * 10.0)
    assert np.allclose(tm.quat_to_mat3(rot)[0], expected, atol=1e-8)


def test_linear_integration_paths_agree():
    pos = rng.normal(size=(100, 3))
    lin = rng.normal(size=(100, 3))
    a, b = pos.copy(), pos.copy()
    tm.integrate_linear(a, lin, 0.1)
    tm.integrate_linear_numpy(b, lin, 0.1)
    assert np.allclose(a, b, rtol=1e-15, atol=1e-15)  # fused multiply-add may differ in the last bit
    assert np.allclose(a, pos + lin * 0.1)


def test_native_kernels_are_compiled_when_numba_is_present():
    pytest.importorskip("numba")
    if not native.AVAILABLE:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    assert tm._compose_native is not None and tm._angular_small is not None and tm._linear_native is not None


def test_systems_give_the_same_result_without_numba(tmp_path):
    """The NumPy fallback (ECS_ENGINE_NO_NUMBA=1) drives the stock systems to the same state."""
    import os
    import subprocess
    import sys

    script = tmp_path / "run.py"
    script.write_text(
        "import sys, numpy as np\n"
        "from ecs_engine import World, Schedule, native\n"
        "from ecs_engine.components import Transform, Velocity, AngularVelocity, Mesh, ModelMatrix\n"
        "from ecs_engine.systems import MotionSystem, TransformSystem\n"
        "rng = np.random.default_rng(3); n = 300\n"
        "w = World()\n"
        "w.spawn_batch(n, Transform(position=rng.normal(size=(n, 3)), rotation=rng.normal(size=(n, 4)),\n"
        "    scale=rng.uniform(-2, 2, size=(n, 3))), Velocity(linear=rng.normal(size=(n, 3))),\n"
        "    AngularVelocity(angular=rng.normal(size=(n, 3))), Mesh())\n"
        "s = Schedule(); s.add(MotionSystem()); s.add(TransformSystem(), 'post_update')\n"
        "for _ in range(5): s.run(w, 1 / 60)\n"
        "q = w.query(ModelMatrix, write=())\n"
        "np.save(sys.argv[1], q.column(ModelMatrix.model))\n"
        "print(native.AVAILABLE)\n"
    )
    results = {}
    for flag in ("0", "1"):
        env = dict(os.environ, ECS_ENGINE_NO_NUMBA=flag)
        out = tmp_path / f"m{flag}.npy"
        proc = subprocess.run(
            [sys.executable, str(script), str(out)], env=env, capture_output=True, text=True, check=True
        )
        results[flag] = (proc.stdout.strip(), np.load(out))
    assert results["1"][0] == "False"
    assert np.allclose(results["0"][1], results["1"][1], atol=1e-5)
