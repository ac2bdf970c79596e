"""The uniform-grid broad phase (maths/broad_phase.py) finds exactly the brute-force pairs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ecs_engine.maths.broad_phase import overlapping_pairs, self_pairs


def brute(a, ra, b, rb):
    d = np.linalg.norm(a[:, None] - b[None], axis=-1)
    ia, ib = np.nonzero(d < (np.broadcast_to(ra, len(a))[:, None] + np.broadcast_to(rb, len(b))[None]))
    return ia, ib


def test_matches_brute_force_on_a_crowd():
    rng = np.random.default_rng(3)
    a = rng.uniform(-20, 20, (2000, 3))
    b = rng.uniform(-20, 20, (500, 3))
    ra, rb = rng.uniform(0.1, 2.0, 2000), rng.uniform(0.1, 1.0, 500)
    got = overlapping_pairs(a, ra, b, rb)
    want = brute(a, ra, b, rb)
    assert len(want[0]) > 100
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
    i, j = self_pairs(a, ra)
    wi, wj = brute(a, ra, a, ra)
    keep = wi < wj
    assert set(zip(i.tolist(), j.tolist())) == set(zip(wi[keep].tolist(), wj[keep].tolist()))


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 40),
    st.integers(0, 40),
    st.floats(0.01, 3.0),
    st.floats(1.0, 8.0),
    st.integers(0, 2**32 - 1),
)
def test_matches_brute_force_for_any_layout(na, nb, radius, cell_scale, seed):
    """Pairs on cell borders, negative coordinates, a larger cell than needed, empty sets."""
    rng = np.random.default_rng(seed)
    a = np.round(rng.uniform(-10, 10, (na, 3)), 1)  # rounded: many exactly on cell borders
    b = np.round(rng.uniform(-10, 10, (nb, 3)), 1)
    ra, rb = rng.uniform(0, radius, na), rng.uniform(0, radius, nb)
    cell = 2 * radius * cell_scale
    got = overlapping_pairs(a, ra, b, rb, cell)
    want = brute(a, ra, b, rb)
    assert got[0].tolist() == want[0].tolist() and got[1].tolist() == want[1].tolist()


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="finite"):
        overlapping_pairs(np.array([[np.nan, 0, 0]]), 1.0, np.zeros((1, 3)), 1.0)
    with pytest.raises(ValueError, match="smaller than the largest diameter"):
        overlapping_pairs(np.zeros((1, 3)), 1.0, np.zeros((1, 3)), 1.0, cell=1.0)
    with pytest.raises(ValueError, match="cells of"):
        overlapping_pairs(np.array([[1e9, 0, 0]]), 1.0, np.zeros((1, 3)), 1.0)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        overlapping_pairs(np.zeros((2, 2)), 1.0, np.zeros((1, 3)), 1.0)


@pytest.mark.parametrize("path", ["dense", "sorted spread", "numpy"])
def test_a_few_spheres_against_many_take_the_spread_paths(monkeypatch, path):
    """A few projectiles against thousands of asteroids: the small set is spread over its 27
    cells (a dense table in the compiled kernel, or sorted keys), the large set never sorted."""
    from ecs_engine import native
    from ecs_engine.maths import broad_phase

    if path == "sorted spread":
        monkeypatch.setattr(broad_phase, "DENSE_CELLS", 1)
    elif path == "numpy":
        monkeypatch.setattr(native, "AVAILABLE", False)
    rng = np.random.default_rng(11)
    many = rng.uniform(-30, 30, (5000, 3))
    few = rng.uniform(-30, 30, (40, 3))
    r_many, r_few = rng.uniform(0.2, 1.5, 5000), rng.uniform(0.1, 0.5, 40)
    for a, ra, b, rb in ((few, r_few, many, r_many), (many, r_many, few, r_few)):
        got = overlapping_pairs(a, ra, b, rb)
        want = brute(a, ra, b, rb)
        assert len(want[0]) > 10
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
