"""A uniform-grid broad phase: which spheres of one set overlap which of another, vectorised.

Space is cut into cubic cells of side `cell` (at least the largest diameter, so an overlapping
pair is always in the same or neighbouring cells), each cell one 63-bit key (21 bits per axis).
Two ways, chosen by the sets' sizes:
- sets of similar size: the larger is binned (its keys sorted), each sphere of the smaller looks
  up its cell and the 26 neighbours with one `searchsorted` over all of them;
- one set SPREAD times smaller or more (a few projectiles against 100,000 asteroids): the small
  set is binned into all 27 cells around each sphere, and each sphere of the large set looks up
  its own cell once, so the large set is never sorted (the game's collisions: 18 -> ~2 ms).
The candidate pairs are expanded with `repeat` and only those closer than the sum of radii kept.
All NumPy: no Python loop over spheres. Tests compare it with the brute-force answer.

Cells are limited to +-2^20 per axis from the origin (a million cells: with 1-unit cells, a
world two million units across); farther spheres are refused with ValueError, as are non-finite
positions or radii.
"""

from __future__ import annotations

import math

import numpy as np

from .. import native

__all__ = ["overlapping_pairs", "self_pairs"]

_BITS = 21
_BIAS = 1 << (_BITS - 1)
SPREAD = 16  # a set this many times smaller than the other is spread over 27 cells instead
DENSE_CELLS = 1 << 22  # the most cells a dense table over the small set's reach may have
_NEIGHBOURS = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)], np.int64)


def _runs(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The positions start, start + 1, ... of every run (starts[k], counts[k]), concatenated."""
    run_first = np.repeat(np.cumsum(counts) - counts, counts)
    return np.repeat(starts, counts) + (np.arange(int(counts.sum())) - run_first)


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
    small_a = len(a) <= len(b)
    few, many = (len(a), len(b)) if small_a else (len(b), len(a))
    if few * SPREAD <= many:  # the few spheres binned into all 27 cells around them
        ia, ib = _spread_pairs(a, ra, b, rb, cell) if small_a else _spread_pairs(b, rb, a, ra, cell)[::-1]
    elif small_a:  # the larger set binned, the smaller queries its 27 cells
        ia, ib = _pairs(a, ra, b, rb, cell)
    else:
        ib, ia = _pairs(b, rb, a, ra, cell)
    sort = np.lexsort((ib, ia))
    return ia[sort], ib[sort]


def _spread_pairs(
    a: np.ndarray, ra: np.ndarray, b: np.ndarray, rb: np.ndarray, cell: float
) -> tuple[np.ndarray, np.ndarray]:
    """The overlapping pairs when a is much smaller: a's spheres binned into every cell they may
    reach (27 keys each, sorted), each sphere of b looks up its own cell once. No sort of b."""
    empty = np.empty(0, np.int64)
    cells_a = _cells(a, cell, "set a")
    if native.AVAILABLE:
        low, high = cells_a.min(axis=0) - 1, cells_a.max(axis=0) + 1
        shape = high - low + 1
        if int(np.prod(shape)) <= DENSE_CELLS:
            return _dense_pairs(a, ra, b, rb, cell, cells_a, low, shape)
    spread = _keys(cells_a[:, None, :] + _NEIGHBOURS[None]).ravel()  # (A * 27,)
    order = np.argsort(spread, kind="stable")
    sorted_keys = spread[order]
    own = _keys(_cells(b, cell, "set b"))
    starts = np.searchsorted(sorted_keys, own, side="left")
    counts = np.searchsorted(sorted_keys, own, side="right") - starts
    hit = np.flatnonzero(counts)
    if not len(hit):
        return empty, empty
    counts, starts = counts[hit], starts[hit]
    ib = np.repeat(hit, counts)
    ia = order[_runs(starts, counts)] // 27
    d = a[ia] - b[ib]
    reach = ra[ia] + rb[ib]
    keep = np.einsum("ij,ij->i", d, d) < reach * reach
    return ia[keep], ib[keep]


def _dense_pairs(
    a: np.ndarray,
    ra: np.ndarray,
    b: np.ndarray,
    rb: np.ndarray,
    cell: float,
    cells_a: np.ndarray,
    low: np.ndarray,
    shape: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """_spread_pairs with a dense table over the box of cells a's spheres reach (a compiled
    kernel): each sphere of b finds its cell's list of a's spheres with one index, and the
    distance test runs in the same pass. About 0.3 ms per 100,000 spheres of b."""
    flat = ((cells_a[:, None, :] + _NEIGHBOURS[None]) - low) @ np.array([shape[1] * shape[2], shape[2], 1])
    flat = flat.ravel()
    order = np.argsort(flat, kind="stable")
    starts = np.zeros(int(np.prod(shape)) + 1, np.int64)
    np.cumsum(np.bincount(flat, minlength=len(starts) - 1), out=starts[1:])
    members = (order // 27).astype(np.int64)
    capacity = max(64, 4 * len(a))
    while True:
        ia = np.empty(capacity, np.int64)
        ib = np.empty(capacity, np.int64)
        found = _dense_kernel(b, rb, a, ra, 1.0 / cell, low, shape, starts, members, ia, ib)  # type: ignore[misc]
        if found <= capacity:
            return ia[:found], ib[:found]
        capacity = found


@native.njit
def _dense_kernel(b, rb, a, ra, inverse_cell, low, shape, starts, members, ia, ib):  # pragma: no cover - compiled
    """Pairs into ia/ib; returns how many there are (more than their length: call again)."""
    found = 0
    for j in range(b.shape[0]):
        x = math.floor(b[j, 0] * inverse_cell) - low[0]
        y = math.floor(b[j, 1] * inverse_cell) - low[1]
        z = math.floor(b[j, 2] * inverse_cell) - low[2]
        if x < 0 or y < 0 or z < 0 or x >= shape[0] or y >= shape[1] or z >= shape[2]:
            continue
        c = (x * shape[1] + y) * shape[2] + z
        for k in range(starts[c], starts[c + 1]):
            i = members[k]
            dx, dy, dz = a[i, 0] - b[j, 0], a[i, 1] - b[j, 1], a[i, 2] - b[j, 2]
            reach = ra[i] + rb[j]
            if dx * dx + dy * dy + dz * dz < reach * reach:
                if found < ia.shape[0]:
                    ia[found] = i
                    ib[found] = j
                found += 1
    return found


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
    ib = order[_runs(starts.ravel(), counts.ravel())]
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
