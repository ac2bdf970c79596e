"""The shapes' bounds in the grid of the engine's rays (ray_grid.py) and the grid's cells they
cover: a shape's reach along the world's axes as it is turned now, its bounds widened by the
grid's margin, and the cells laid out with room to spare (ray_refresh.py moves a shape into
other cells without making the grid again)."""

from __future__ import annotations

import numpy as np

from .. import native
from ..components.physics import BOX, CAPSULE, SPHERE
from ..native import fetch_add
from .ray_shapes import turn_at

SPARE = 2  # room for this many more shapes in every cell, and a quarter of those it holds
BLOCK = 2048  # shapes a thread takes at a time while the grid is made


def _reach_kernel(rotations, r, s, s0, s1, s2):  # pragma: no cover
    """How far a shape of kind s and Collider sizes s0..s2, turned as the body at row r of the
    library's buffers, reaches from its centre along the world's x, y and z."""
    m0, m1, m2, m3, m4, m5, m6, m7, m8 = turn_at(rotations, r)
    if s == BOX:
        ex = abs(m0) * s0 + abs(m1) * s1 + abs(m2) * s2
        ey = abs(m3) * s0 + abs(m4) * s1 + abs(m5) * s2
        ez = abs(m6) * s0 + abs(m7) * s1 + abs(m8) * s2
    elif s == SPHERE:
        ex = ey = ez = s0
    elif s == CAPSULE:  # along local y: radius size[0], half height size[1]
        ex, ey, ez = abs(m1) * s1 + s0, abs(m4) * s1 + s0, abs(m7) * s1 + s0
    else:  # a cylinder: its caps are discs across the axis
        ex = abs(m1) * s1 + s0 * np.sqrt(max(0.0, 1.0 - m1 * m1))
        ey = abs(m4) * s1 + s0 * np.sqrt(max(0.0, 1.0 - m4 * m4))
        ez = abs(m7) * s1 + s0 * np.sqrt(max(0.0, 1.0 - m7 * m7))
    # (wide enough that rounding never leaves a hit outside)
    return ex + 1e-6 * ex + 1e-9, ey + 1e-6 * ey + 1e-9, ez + 1e-6 * ez + 1e-9


_reach = native.inner(_reach_kernel)


def _bound_kernel(positions, rotations, r, s, s0, s1, s2, margin, bounds, i):  # pragma: no cover
    """bounds[i]: the world bounds of a shape (kind s, Collider sizes s0..s2) posed as the body
    at row r of the buffers, `margin` wider all round (low x y z, high x y z)."""
    reach = _reach(rotations, r, s, s0, s1, s2)
    for a in range(3):
        c = positions[r, a]
        e = reach[a] + margin + 1e-6 * abs(c)
        bounds[i, a], bounds[i, 3 + a] = c - e, c + e


bound = native.inner(_bound_kernel)


def _take_kernel(claims, i, block, count):  # pragma: no cover
    """The next block of `count` rows for this thread, from the counter claims[i]: (first,
    last), empty once every row is taken."""
    first = min(fetch_add(claims, i, block), count)
    return first, min(count, first + block)


take = native.inner(_take_kernel)


def _bounds_kernel(
    claims, block, positions, rotations, rows, shape, size, big, margin, bounds, parts
):  # pragma: no cover
    """Each shape's bounds (`bound`), in blocks of `block` shapes taken from claims[0] (by the
    threads making the grid, or one), and parts[b], the extent of block b's shapes that are
    not `big` (low, then high)."""
    while True:
        first, last = take(claims, 0, block, len(rows))
        if first == last:
            break
        b = first // block
        parts[b, 0, :], parts[b, 1, :] = np.inf, -np.inf
        for i in range(first, last):
            bound(positions, rotations, rows[i], shape[i], size[i, 0], size[i, 1], size[i, 2], margin, bounds, i)
            if not big[i]:
                for a in range(3):
                    parts[b, 0, a], parts[b, 1, a] = (
                        min(parts[b, 0, a], bounds[i, a]),
                        max(parts[b, 1, a], bounds[i, 3 + a]),
                    )


def _cells_kernel(bounds, j, origin, inv_cell, dims):  # pragma: no cover
    """The cells shape j's bounds cover: (x0, y0, z0, x1, y1, z1), inclusive. (Truncating a
    number clamped at 0 floors it, as the cast's walk does.)"""
    x0 = min(int(max((bounds[j, 0] - origin[0]) * inv_cell, 0.0)), dims[0] - 1)
    y0 = min(int(max((bounds[j, 1] - origin[1]) * inv_cell, 0.0)), dims[1] - 1)
    z0 = min(int(max((bounds[j, 2] - origin[2]) * inv_cell, 0.0)), dims[2] - 1)
    x1 = min(int(max((bounds[j, 3] - origin[0]) * inv_cell, 0.0)), dims[0] - 1)
    y1 = min(int(max((bounds[j, 4] - origin[1]) * inv_cell, 0.0)), dims[1] - 1)
    z1 = min(int(max((bounds[j, 5] - origin[2]) * inv_cell, 0.0)), dims[2] - 1)
    return x0, y0, z0, x1, y1, z1


cells = native.inner(_cells_kernel)


def _store_kernel(boxes, at, bounds, j):  # pragma: no cover
    """boxes[at] = bounds[j] in float32, rounded outward (half the memory of float64 to read
    per item, and never narrower than the bounds)."""
    for a in range(3):
        low, high = bounds[j, a], bounds[j, 3 + a]
        boxes[at, a] = np.float32(low - 1e-7 * abs(low) - 1e-30)
        boxes[at, 3 + a] = np.float32(high + 1e-7 * abs(high) + 1e-30)


store = native.inner(_store_kernel)


def _insert_kernel(layout, bounds, j, shared):  # pragma: no cover
    """Shape j put into every cell its bounds cover, as far as the first without room (the
    cells before it keep it): whether every cell took it. `layout`: the grid's (origin, cell,
    dims, starts, fill, items, boxes), RayGrid's. `shared`: threads put shapes in at once,
    each slot taken for every thread at once (room counted beforehand)."""
    origin, cell, dims, starts, fill, items, boxes = layout
    x0, y0, z0, x1, y1, z1 = cells(bounds, j, origin, 1.0 / cell, dims)
    for cz in range(z0, z1 + 1):
        for cy in range(y0, y1 + 1):
            for cx in range(x0, x1 + 1):
                c = (cz * dims[1] + cy) * dims[0] + cx
                if shared:
                    at = starts[c] + fetch_add(fill, c, 1)
                else:
                    at = starts[c] + fill[c]
                    if at == starts[c + 1]:
                        return False
                    fill[c] += 1
                items[at] = j
                store(boxes, at, bounds, j)
    return True


insert = native.inner(_insert_kernel)


def _count_kernel(claims, block, bounds, small, origin, cell, dims, counts, shared):  # pragma: no cover
    """counts[c]: how many of the `small` shapes' bounds cover cell c, in blocks of `block`
    shapes taken from claims[1] (adding at once for every thread where `shared`)."""
    while True:
        first, last = take(claims, 1, block, len(small))
        if first == last:
            return
        for k in range(first, last):
            x0, y0, z0, x1, y1, z1 = cells(bounds, small[k], origin, 1.0 / cell, dims)
            for cz in range(z0, z1 + 1):
                for cy in range(y0, y1 + 1):
                    for cx in range(x0, x1 + 1):
                        c = (cz * dims[1] + cy) * dims[0] + cx
                        if shared:
                            fetch_add(counts, c, 1)
                        else:
                            counts[c] += 1


def _starts_kernel(counts):  # pragma: no cover
    """Each cell's first slot, with room for its shapes and to spare (SPARE, and a quarter
    more); `counts` zeroed, to be the cells' fill."""
    starts = np.zeros(len(counts) + 1, np.int32)
    for c in range(len(counts)):
        starts[c + 1] = starts[c] + counts[c] + SPARE + counts[c] // 4
        counts[c] = 0
    return starts


def _place_kernel(claims, block, bounds, small, layout, shared):  # pragma: no cover
    """The `small` shapes put into the cells their bounds cover (room counted by _count), in
    blocks of `block` taken from claims[2] (`shared`: by threads at once, so the order in a cell
    varies, which no answer depends on)."""
    first, last = take(claims, 2, block, len(small))
    while first < last:
        for k in range(first, last):
            insert(layout, bounds, small[k], shared)
        first, last = take(claims, 2, block, len(small))


bounds_of = native.njit(_bounds_kernel)
count_cells = native.njit(_count_kernel)
starts_of = native.njit(_starts_kernel)
place_cells = native.njit(_place_kernel)
