"""The chunk kernel (numba) and its NumPy reference write the same rows in the same order."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine.maths.camera import perspective, view_rotation, yaw_pitch_quat
from ecs_engine.maths.culling import frustum_planes
from ecs_engine.maths.transform import compose
from ecs_engine.render.draw import instance_rows as ir

rng = np.random.default_rng(4)


def chunk(n=3000, meshes=3):
    pos = rng.uniform(-40, 40, size=(n, 3))
    q = rng.normal(size=(n, 4))
    scale = rng.uniform(0.2, 2.0, size=(n, 3)) * np.where(rng.random((n, 1)) < 0.2, -1.0, 1.0)
    model = np.empty((n, 4, 4), np.float32)
    normal = np.empty((n, 3, 3), np.float32)
    compose(pos, q, scale, np.zeros(3), model, normal)
    handle = rng.integers(0, meshes, size=n).astype(np.uint32)
    material = rng.integers(0, 50, size=n).astype(np.uint32)
    centers = rng.normal(scale=0.1, size=(meshes, 3))
    radii = rng.uniform(0.5, 1.5, size=meshes)
    return model, handle, material, centers, radii


@pytest.mark.parametrize("cull", [True, False])
def test_kernel_matches_reference(cull):
    if ir._write_rows_native is None:
        pytest.skip("numba not available")
    model, handle, material, centers, radii = chunk()
    planes = frustum_planes(perspective(1.0, 1.5, 0.1), view_rotation(yaw_pitch_quat(0.4, 0.1))) if cull else None
    out = []
    for fn in (ir.write_rows, ir.write_rows_numpy):
        rows = np.zeros(len(handle), ir.INSTANCE_DTYPE)
        rows.view(np.uint8)[:] = 0xAB  # poison: every written byte must be overwritten
        counts = np.full(6, -1, np.int64)
        p = ir.NO_PLANES if planes is None else planes
        n = fn(model, handle, material, centers, radii, p, 6, rows, counts)
        out.append((n, rows[:n].copy(), counts))
    (n1, r1, c1), (n2, r2, c2) = out
    assert n1 == n2 and np.array_equal(c1, c2) and c1.sum() == n1
    assert (0 < n1 < len(handle)) if cull else n1 == len(handle)
    assert r1.tobytes() == r2.tobytes()
    assert c1[1::2].sum() > 0  # some mirrored rows, sorted after the plain ones of their mesh


@pytest.mark.parametrize("native", [True, False])
def test_views_culled_at_once_write_what_one_view_writes(native, monkeypatch):
    """cull_views + write_keyed (the shadow jobs: every view of a chunk in one pass) write, per
    view, the rows and key counts write_rows writes for that view alone; with and without numba."""
    if native and ir._cull_views_native is None:
        pytest.skip("numba not available")
    if not native:
        monkeypatch.setattr(ir, "_cull_views_native", None)
        monkeypatch.setattr(ir, "_write_keyed_native", None)
    model, handle, material, centers, radii = chunk()
    views = [
        frustum_planes(perspective(1.0, 1.5, 0.1), view_rotation(yaw_pitch_quat(yaw, 0.1))) for yaw in (0.4, 2.0, -1.3)
    ] + [None, frustum_planes(perspective(0.6, 1.0, 0.1, 30.0), view_rotation(yaw_pitch_quat(0.0, 0.0)))]
    planes = ir.padded_planes(views)
    keys = np.empty((len(views), len(handle)), np.int32)
    counts = np.full((len(views), 6), -1, np.int64)
    ir.cull_views(model, handle, centers, radii, planes, keys, counts)
    seen = set()
    for v, p in enumerate(views):
        expected = np.zeros(len(handle), ir.INSTANCE_DTYPE)
        expected_counts = np.zeros(6, np.int64)
        p = ir.NO_PLANES if p is None else p
        n = ir.write_rows_numpy(model, handle, material, centers, radii, p, 6, expected, expected_counts)
        rows = np.zeros(len(handle), ir.INSTANCE_DTYPE)
        rows.view(np.uint8)[:] = 0xAB
        assert ir.write_keyed(model, material, keys[v], counts[v], 6, rows) == n
        assert np.array_equal(counts[v], expected_counts)
        assert rows[:n].tobytes() == expected[:n].tobytes()
        seen.add(n)
    assert len(seen) == len(views) and len(handle) in seen and 0 < min(seen)  # views that differ, one keeping all
