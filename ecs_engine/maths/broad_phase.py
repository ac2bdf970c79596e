"""A uniform-grid broad phase: which spheres of one set overlap which of another, vectorised.

The larger set is binned into cubic cells of side `cell` (at least the largest diameter, so an
overlapping pair is always in the same or neighbouring cells): each cell is one 63-bit key (21
bits per axis), the keys sorted once. Each sphere of the other set then looks up its cell and its
26 neighbours with one `searchsorted` over all of them (the smaller set queries), the candidate pairs are expanded with
`repeat`, and only those closer than the sum of radii are kept. All NumPy: no Python loop over
spheres. Tests compare it with the brute-force all-pairs answer.

Cells are limited to +-2^20 per axis from the origin (a million cells: with 1-unit cells, a
world two million units across); farther spheres are refused with ValueError, as are non-finite
positions or radii.
"""

from __future__ import annotations

import numpy as np

__all__ = ["overlapping_pairs", "self_pairs"]

_BITS = 21
_BIAS = 1 << (_BITS - 1)
_NEIGHBOURS = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)], np.int64)


def _keys(cells: np.ndarray) -> np.ndarray:
    c = cells + _BIAS
    return (c[..., 0] << (2 * _BITS)) | (c[..., 1] << _BITS) | c[..., 2]


def _cells(positions: np.ndarray, cell: float, what: str) -> np.ndarray:
    cells = np.floor(positions / cell).astype(np.int64)
    if cells.size and (np.abs(cells).max() >= _BIAS - 1):
        raise ValueError(f"{what}: a position lies more than {_BIAS - 1} cells of {cell} from the origin")
    return cells


def _check(positions: np.ndarray, radii: np.ndarray | float, what: str) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(positions, np.float64)
    r = np.broadcast_to(np.asarray(radii, np.float64), p.shape[:1])
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"{what}: positions must be (N, 3), got {p.shape}")
    if not (np.isfinite(p).all() and np.isfinite(r).all()) or (r < 0).any():
        raise ValueError(f"{what}: positions and radii must be finite, radii not negative")
    return p, r


def overlapping_pairs(
    a_positions: np.ndarray,
    a_radii: np.ndarray | float,
    b_positions: np.ndarray,
    b_radii: np.ndarray | float,
    cell: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(ia, ib): every pair of a sphere of set a and one of set b that overlap (distance below
    the sum of the radii), as index arrays sorted by ia then ib. `cell` defaults to the largest
    diameter in either set."""
    a, ra = _check(a_positions, a_radii, "set a")
    b, rb = _check(b_positions, b_radii, "set b")
    empty = np.empty(0, np.int64)
    if not len(a) or not len(b):
        return empty, empty
    if cell is None:
        cell = 2.0 * max(float(ra.max()), float(rb.max()))
    cell = max(float(cell), 1e-9)
    if 2.0 * max(float(ra.max()), float(rb.max())) > cell * (1 + 1e-12):
        raise ValueError(f"cell {cell} is smaller than the largest diameter: pairs could be missed")
    if len(a) > len(b):  # bin the larger set, query with the smaller: 27 lookups per query sphere
        ib, ia = _pairs(b, rb, a, ra, cell)
    else:
        ia, ib = _pairs(a, ra, b, rb, cell)
    sort = np.lexsort((ib, ia))
    return ia[sort], ib[sort]


def _pairs(a: np.ndarray, ra: np.ndarray, b: np.ndarray, rb: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """The overlapping pairs, b binned and a querying, unsorted."""
    empty = np.empty(0, np.int64)
    b_keys = _keys(_cells(b, cell, "set b"))
    order = np.argsort(b_keys, kind="stable")
    sorted_keys = b_keys[order]
    wanted = _keys(_cells(a, cell, "set a")[:, None, :] + _NEIGHBOURS[None])  # (A, 27)
    starts = np.searchsorted(sorted_keys, wanted, side="left")
    counts = np.searchsorted(sorted_keys, wanted, side="right") - starts
    total = int(counts.sum())
    if total == 0:
        return empty, empty
    ia = np.repeat(np.repeat(np.arange(len(a)), 27), counts.ravel())
    # position k of the expansion within its run: k - the run's first position
    run_first = np.repeat(np.cumsum(counts.ravel()) - counts.ravel(), counts.ravel())
    slot = np.repeat(starts.ravel(), counts.ravel()) + (np.arange(total) - run_first)
    ib = order[slot]
    d = a[ia] - b[ib]
    reach = ra[ia] + rb[ib]
    keep = np.einsum("ij,ij->i", d, d) < reach * reach
    return ia[keep], ib[keep]


def self_pairs(
    positions: np.ndarray, radii: np.ndarray | float, cell: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(i, j), i < j: every overlapping pair within one set of spheres."""
    i, j = overlapping_pairs(positions, radii, positions, radii, cell)
    keep = i < j
    return i[keep], j[keep]
