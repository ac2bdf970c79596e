"""The walk of the engine's rays through a grid of the shapes' bounds (ray_grid.py): per ray,
the grid's cells in the ray's order (Amanatides and Woo), each cell's shapes tested by their
bounds and then exactly (ray_shapes.py), then the shapes too large for the grid (a floor)
whose bounds the ray meets before its nearest hit. Compiled, the GIL released:
threads cast rays side by side (numba's own, started together: ray_spread.py), each taking
the next RAY_BLOCK rays from a counter they share until none are left (a thread that starts
late takes fewer)."""

from __future__ import annotations

import numpy as np

from .. import native
from .ray_bounds import bound, take
from .ray_shapes import shape_hit

RAY_BLOCK = 64  # rays a thread takes at a time (about 15 us of work on the GPU host's cores)


def claims() -> np.ndarray:
    """The counter of rays taken, for the threads casting one batch to share."""
    return np.zeros(1, np.int64)


def _inverse_kernel(d):  # pragma: no cover
    """1 / d, or a huge number of d's sign where d is 0 (the bounds test stays free of NaN)."""
    return 1.0 / d if abs(d) > 1e-300 else (-1e300 if np.signbit(d) else 1e300)


def _meets_kernel(bounds, j, ox, oy, oz, ix, iy, iz, best):  # pragma: no cover
    """Whether the ray (from o, 1 / its direction i) meets bounds[j] before best."""
    t1, t2 = (bounds[j, 0] - ox) * ix, (bounds[j, 3] - ox) * ix
    enter, leave = min(t1, t2), max(t1, t2)
    t1, t2 = (bounds[j, 1] - oy) * iy, (bounds[j, 4] - oy) * iy
    enter, leave = max(enter, min(t1, t2)), min(leave, max(t1, t2))
    t1, t2 = (bounds[j, 2] - oz) * iz, (bounds[j, 5] - oz) * iz
    enter, leave = max(enter, min(t1, t2)), min(leave, max(t1, t2))
    return enter <= leave and leave >= 0.0 and enter <= best


_inverse = native.inner(_inverse_kernel)
_meets = native.inner(_meets_kernel)


def _cast_kernel(  # pragma: no cover
    origins,
    directions,
    max_t,
    claims,
    positions,
    rotations,
    rows,
    shape,
    size,
    large,
    layout,
    bounds,
    spill,
    answer,
    out_shape,
    out_t,
    out_point,
    out_normal,
):
    """Rays in blocks of RAY_BLOCK taken from claims[0] (shared by the threads casting them)
    until none are left: the nearest shape each meets within max_t (out_shape: answer[the
    shape's index]; -1: none; -2: the ray's origin or direction is not finite, or the direction
    is zero), the distance, the point and the normal (NaN without a hit). The grid's cells (its
    `layout`, RayGrid's) in the ray's order, stopping at the first cell whose exit lies past the
    nearest hit so far, then the shapes spilt out of the cells (`spill`: their count, then they;
    by their `bounds` first) and the large shapes. A shape is looked at once a ray (`seen`: the
    last ray that looked at it), and tested exactly only when the ray meets its bounds before
    the nearest hit so far. Of shapes hit at the same distance (a ray starting inside two) the
    one of the lower index is answered, whatever order the cells hold them in."""
    origin, cell, dims, starts, fill, items, boxes = layout
    nx, ny, nz = dims[0], dims[1], dims[2]
    inv_cell = 1.0 / cell
    seen = np.full(len(shape), -1, np.int64)
    large_bounds = np.empty((len(large), 6))
    for n in range(len(large)):
        j = large[n]
        bound(positions, rotations, rows[j], shape[j], size[j, 0], size[j, 1], size[j, 2], 0.0, large_bounds, n)
    while True:
        first, last = take(claims, 0, RAY_BLOCK, len(origins))
        if first == last:
            break
        for k in range(first, last):
            ox, oy, oz = origins[k, 0], origins[k, 1], origins[k, 2]
            dx, dy, dz = directions[k, 0], directions[k, 1], directions[k, 2]
            length = np.sqrt(dx * dx + dy * dy + dz * dz)
            # (comparisons: np.isfinite answered True for NaN here, under the engine's fastmath flags)
            if not (abs(ox + oy + oz) < np.inf and 0.0 < length < np.inf):
                out_shape[k] = -2
                continue
            dx, dy, dz = dx / length, dy / length, dz / length
            ix, iy, iz = _inverse(dx), _inverse(dy), _inverse(dz)
            best, hit, hx, hy, hz = max_t, -1, 0.0, 0.0, 0.0
            # the ray's part inside the grid's box
            enter, leave = 0.0, best
            o3, d3 = (ox, oy, oz), (dx, dy, dz)
            for a in range(3):
                top = origin[a] + dims[a] * cell
                if abs(d3[a]) < 1e-300:
                    if o3[a] < origin[a] or o3[a] > top:
                        leave = -1.0
                    continue
                t1, t2 = (origin[a] - o3[a]) / d3[a], (top - o3[a]) / d3[a]
                if t1 > t2:
                    t1, t2 = t2, t1
                enter, leave = max(enter, t1), min(leave, t2)
            if len(items) and enter <= leave:
                cx = min(max(int(np.floor((ox + dx * enter - origin[0]) * inv_cell)), 0), nx - 1)
                cy = min(max(int(np.floor((oy + dy * enter - origin[1]) * inv_cell)), 0), ny - 1)
                cz = min(max(int(np.floor((oz + dz * enter - origin[2]) * inv_cell)), 0), nz - 1)
                sx, sy, sz = (1 if dx > 0 else -1), (1 if dy > 0 else -1), (1 if dz > 0 else -1)
                # the distance to each axis's next cell wall, and between walls
                ex = (origin[0] + (cx + (sx > 0)) * cell - ox) / dx if dx != 0.0 else np.inf
                ey = (origin[1] + (cy + (sy > 0)) * cell - oy) / dy if dy != 0.0 else np.inf
                ez = (origin[2] + (cz + (sz > 0)) * cell - oz) / dz if dz != 0.0 else np.inf
                gx = cell / abs(dx) if dx != 0.0 else np.inf
                gy = cell / abs(dy) if dy != 0.0 else np.inf
                gz = cell / abs(dz) if dz != 0.0 else np.inf
                while True:
                    c0 = (cz * ny + cy) * nx + cx
                    for m in range(starts[c0], starts[c0] + fill[c0]):
                        j = items[m]
                        if seen[j] == k:  # (in an earlier cell: its bounds are the same here)
                            continue
                        seen[j] = k
                        if not _meets(boxes, m, ox, oy, oz, ix, iy, iz, best):
                            continue
                        s0, s1, s2 = size[j, 0], size[j, 1], size[j, 2]
                        t, a, b, c = shape_hit(
                            ox, oy, oz, dx, dy, dz, positions, rotations, rows[j], shape[j], s0, s1, s2
                        )
                        if t < best or (t == best and (hit < 0 or j < hit)):
                            best, hit, hx, hy, hz = t, j, a, b, c
                    out = min(ex, ey, ez)
                    if best <= out or out > leave:
                        break
                    if ex == out:
                        cx, ex = cx + sx, ex + gx
                        if cx < 0 or cx >= nx:
                            break
                    elif ey == out:
                        cy, ey = cy + sy, ey + gy
                        if cy < 0 or cy >= ny:
                            break
                    else:
                        cz, ez = cz + sz, ez + gz
                        if cz < 0 or cz >= nz:
                            break
            for n in range(1, spill[0] + 1):  # shapes outside the grid's cells
                j = spill[n]
                if seen[j] != k and _meets(bounds, j, ox, oy, oz, ix, iy, iz, best):
                    s0, s1, s2 = size[j, 0], size[j, 1], size[j, 2]
                    t, a, b, c = shape_hit(ox, oy, oz, dx, dy, dz, positions, rotations, rows[j], shape[j], s0, s1, s2)
                    if t < best or (t == best and (hit < 0 or j < hit)):
                        best, hit, hx, hy, hz = t, j, a, b, c
            for n in range(len(large)):  # past the grid's hit, their bounds say, as a floor is
                if _meets(large_bounds, n, ox, oy, oz, ix, iy, iz, best):
                    j = large[n]
                    s0, s1, s2 = size[j, 0], size[j, 1], size[j, 2]
                    t, a, b, c = shape_hit(ox, oy, oz, dx, dy, dz, positions, rotations, rows[j], shape[j], s0, s1, s2)
                    if t < best or (t == best and (hit < 0 or j < hit)):
                        best, hit, hx, hy, hz = t, j, a, b, c
            out_shape[k] = answer[hit] if hit >= 0 else -1
            if hit < 0:
                best = hx = hy = hz = np.nan
            out_t[k] = best
            out_point[k, 0], out_point[k, 1], out_point[k, 2] = ox + dx * best, oy + dy * best, oz + dz * best
            out_normal[k, 0], out_normal[k, 1], out_normal[k, 2] = hx, hy, hz


cast_rays = native.njit(_cast_kernel)
