"""The GGX-prefiltered specular chain (render/lighting/environment_prefilter.py): every blurred level
matches the split sum's lobe integral over the sharp faces, computed here by brute force over
every texel; the NumPy fallback and the numba kernel agree; the job pool's blocks give the serial
result; a uniform sky stays uniform; roughness reaches 1 on 4 x 4 faces."""

from __future__ import annotations

import numpy as np
import pytest
from shading_reference import lobe_integral

from ecs_engine import native
from ecs_engine.jobs import JobPool
from ecs_engine.render.lighting import environment_prefilter
from ecs_engine.render.lighting.environment_maps import cube_directions
from ecs_engine.render.lighting.environment_prefilter import ggx_prefiltered_mips, level_roughness, roughness_levels

SIDE = 16
SUN = np.array([0.3, 0.8, -0.5]) / np.linalg.norm([0.3, 0.8, -0.5])


def sky(side: int = SIDE) -> np.ndarray:
    """A smooth gradient plus a small sun 20 times brighter (the case that makes fireflies)."""
    d = cube_directions(side)
    gradient = (1.0 + 0.5 * d[..., :1] + d[..., 1:2] ** 2) * np.array([1.0, 0.8, 0.6])
    sun = 20.0 * np.exp(-60.0 * (1.0 - d @ SUN))[..., None]
    return (gradient + sun).astype(np.float32)


def test_roughness_reaches_one_on_four_by_four_faces():
    assert [roughness_levels(n) for n in (1, 2, 3, 4, 5, 11)] == [0, 1, 2, 1, 2, 8]
    assert [level_roughness(k, 5) for k in range(5)] == [0.0, 0.5, 1.0, 1.0, 1.0]
    chain = ggx_prefiltered_mips(sky())
    assert [level.shape for level in chain] == [(6, s, s, 3) for s in (16, 8, 4, 2, 1)]
    assert chain[roughness_levels(len(chain))].shape[1] == 4


@pytest.mark.parametrize(("side", "small", "mean", "most"), [(SIDE, 16, 0.005, 0.04), (32, 1, 0.02, 0.15)])
def test_each_level_is_the_ggx_lobe_integral(monkeypatch, side, small, mean, most):
    """Small faces take the most samples; with `small` 1 every level takes the doubling counts
    from SAMPLES (64 at the first blurred level): a looser match, no sun-sized fireflies."""
    monkeypatch.setattr(environment_prefilter, "SMALL", small)
    faces = sky(side)
    chain = ggx_prefiltered_mips(faces)
    np.testing.assert_array_equal(chain[0], faces)
    for level in range(1, len(chain)):
        normals = cube_directions(chain[level].shape[1]).reshape(-1, 3)
        expected = lobe_integral(faces, normals, level_roughness(level, len(chain)))
        error = np.abs(chain[level].reshape(-1, 3) - expected) / expected
        assert error.mean() < mean, (level, error.mean())
        assert error.max() < most, (level, error.max())
    faces = sky()
    chain = ggx_prefiltered_mips(faces)
    # the blur is real: the sun's texel at roughness 0.5 is far below its sharp value
    sun_texel = np.argmax(cube_directions(8).reshape(-1, 3) @ SUN)
    assert chain[1].reshape(-1, 3)[sun_texel, 0] < 0.5 * faces.reshape(-1, 3).max()


def test_a_uniform_sky_stays_uniform_at_every_roughness():
    faces = np.full((6, 32, 32, 3), (0.25, 0.5, 2.0), np.float32)
    for level in ggx_prefiltered_mips(faces):
        np.testing.assert_allclose(level, faces[:, : level.shape[1], : level.shape[1]], rtol=1e-5)


def test_numpy_fallback_and_blocks_on_the_job_pool_agree(monkeypatch):
    if not native.AVAILABLE:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    faces = sky(32)
    compiled = ggx_prefiltered_mips(faces)
    pool = JobPool(2)
    try:
        monkeypatch.setattr(environment_prefilter, "BLOCK", 100)  # many blocks, a short last one
        pooled = ggx_prefiltered_mips(faces, map_blocks=pool.map)
    finally:
        pool.close()
    for a, b in zip(compiled, pooled):
        np.testing.assert_array_equal(a, b)
    monkeypatch.setattr(native, "AVAILABLE", False)
    fallback = ggx_prefiltered_mips(faces)
    for a, b in zip(compiled, fallback):
        # the kernel's fused multiply-adds round differently: a sample that lands on a cube edge
        # can read the other face's clamped texels (seen: 6 texels of 4,608, up to 2%)
        error = np.abs(a - b) / np.maximum(np.abs(b), 1e-6)
        assert (error < 1e-5).mean() > 0.99
        assert error.max() < 0.05


def test_faces_must_be_a_power_of_two():
    with pytest.raises(ValueError, match="power-of-two"):
        ggx_prefiltered_mips(np.zeros((6, 12, 12, 3), np.float32))
