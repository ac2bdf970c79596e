"""Rays against the bodies' primitive shapes (boxes, spheres, capsules, cylinders), cast by the
engine in compiled loops that release the GIL, over a uniform grid of the shapes' bounds.

Why not the library's batch: culverin's reads each hit's body through Jolt's locking body
interface, so its threads contend: 10,000 rays on a pile of 10,000 boxes took 4.3-4.8 ms on 8
to 16 threads of the GPU host, this cast 2.8 (docs/physics.md). The primitives' poses are in the
library's shared buffers already; a grid of their bounds is made once per step (or when a body
is placed) and every ray walks it cell by cell (Amanatides and Woo), testing a shape's bounds
and then its exact shape (ray_shapes.py), as the library does, in float64. Shapes too big for
the grid's cells (a floor) are tested by every ray."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import native
from ..components.physics import BOX, CAPSULE, SPHERE
from .ray_shapes import shape_hit

CELL_REACH = 0.7  # the grid's cell, in the median shape's reach (its bounding sphere's diameter)
MARGIN = 0.02  # the shapes' bounds in the grid are this many cells wider all round: the grid
# stands for the steps after it was made until a shape moves further than that
LARGE_CELLS = 64  # a shape over more cells than this is tested by every ray instead
CELLS_PER_SHAPE = 4  # the grid has at most this many cells per shape (more for far-apart shapes)


def _reach_kernel(rotations, r, s, s0, s1, s2, a):  # pragma: no cover
    """How far a shape of kind s and Collider sizes s0..s2, turned as the body at row r of the
    library's buffers, reaches from its centre along world axis a."""
    x, y = np.float64(rotations[r, 0]), np.float64(rotations[r, 1])
    z, w = np.float64(rotations[r, 2]), np.float64(rotations[r, 3])
    inv = 2.0 / (x * x + y * y + z * z + w * w)
    # row a of the rotation matrix (of the quaternion made unit)
    if a == 0:
        k0, k1, k2 = 1 - (y * y + z * z) * inv, (x * y - z * w) * inv, (x * z + y * w) * inv
    elif a == 1:
        k0, k1, k2 = (x * y + z * w) * inv, 1 - (x * x + z * z) * inv, (y * z - x * w) * inv
    else:
        k0, k1, k2 = (x * z - y * w) * inv, (y * z + x * w) * inv, 1 - (x * x + y * y) * inv
    if s == BOX:
        e = abs(k0) * s0 + abs(k1) * s1 + abs(k2) * s2
    elif s == SPHERE:
        e = s0
    elif s == CAPSULE:  # along local y: radius size[0], half height size[1]
        e = abs(k1) * s1 + s0
    else:  # a cylinder: its caps are discs across the axis
        e = abs(k1) * s1 + s0 * np.sqrt(max(0.0, 1.0 - k1 * k1))
    return e + 1e-6 * e + 1e-9  # (wide enough that rounding never leaves a hit outside)


def _bounds_kernel(positions, rotations, rows, shape, size, big, margin, bounds, extent):  # pragma: no cover
    """Each shape's world bounds from the buffers, `margin` wider all round (bounds: low x y z,
    high x y z), and `extent`, the bounds of the shapes that are not `big` (low, then
    high)."""
    extent[0, :], extent[1, :] = np.inf, -np.inf
    for i in range(len(rows)):
        r = rows[i]
        for a in range(3):
            c = positions[r, a]
            e = _reach(rotations, r, shape[i], size[i, 0], size[i, 1], size[i, 2], a) + margin + 1e-6 * abs(c)
            bounds[i, a], bounds[i, 3 + a] = c - e, c + e
            if not big[i]:
                extent[0, a], extent[1, a] = min(extent[0, a], c - e), max(extent[1, a], c + e)


def _pose_kernel(positions, rotations, rows, pose):  # pragma: no cover
    """Each shape's pose now: its centre and its rotation made unit (x, y, z, w)."""
    for i in range(len(rows)):
        r = rows[i]
        x, y = np.float64(rotations[r, 0]), np.float64(rotations[r, 1])
        z, w = np.float64(rotations[r, 2]), np.float64(rotations[r, 3])
        inv = 1.0 / np.sqrt(x * x + y * y + z * z + w * w)
        pose[i, 0], pose[i, 1], pose[i, 2] = positions[r, 0], positions[r, 1], positions[r, 2]
        pose[i, 3], pose[i, 4], pose[i, 5], pose[i, 6] = x * inv, y * inv, z * inv, w * inv


def _escaped_kernel(positions, rotations, rows, big, radius, pose, margin):  # pragma: no cover
    """Whether any shape that is not `big` may reach outside the bounds the grid was made with
    (`margin` wider than it was at `pose`). No point of a shape has moved further than its
    centre has plus its radius times the turn's chord, 2 |q - q0| for unit quaternions on the
    same side; while that stays within the margin the grid holds every shape in its cells."""
    for i in range(len(rows)):
        if big[i]:
            continue
        r = rows[i]
        dx, dy, dz = positions[r, 0] - pose[i, 0], positions[r, 1] - pose[i, 1], positions[r, 2] - pose[i, 2]
        x, y = np.float64(rotations[r, 0]), np.float64(rotations[r, 1])
        z, w = np.float64(rotations[r, 2]), np.float64(rotations[r, 3])
        inv = 1.0 / np.sqrt(x * x + y * y + z * z + w * w)
        if x * pose[i, 3] + y * pose[i, 4] + z * pose[i, 5] + w * pose[i, 6] < 0.0:
            inv = -inv
        qx, qy, qz, qw = x * inv - pose[i, 3], y * inv - pose[i, 4], z * inv - pose[i, 5], w * inv - pose[i, 6]
        moved = np.sqrt(dx * dx + dy * dy + dz * dz) + 2.0 * radius[i] * np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if moved > margin:
            return True
    return False


_reach = native.inner(_reach_kernel)


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


def _fill_kernel(bounds, small, origin, inv_cell, dims):  # pragma: no cover
    """The grid's cells as ranges of items (shape indices): (starts, items, boxes), starts with
    a row per cell and one more, boxes the items' bounds beside them (a cell's are read in a
    row, not gathered by shape). Two passes: count each cell's shapes, then place them."""
    nx, ny = dims[0], dims[1]
    starts = np.zeros(dims[0] * dims[1] * dims[2] + 1, np.int32)
    for k in range(len(small)):
        x0, y0, z0, x1, y1, z1 = _cells(bounds, small[k], origin, inv_cell, dims)
        for cz in range(z0, z1 + 1):
            for cy in range(y0, y1 + 1):
                for cx in range(x0, x1 + 1):
                    starts[(cz * ny + cy) * nx + cx + 1] += 1
    for c in range(len(starts) - 1):
        starts[c + 1] += starts[c]
    items, boxes = np.empty(starts[-1], np.int32), np.empty((starts[-1], 6), np.float64)
    cursor = starts[:-1].copy()
    for k in range(len(small)):
        j = small[k]
        x0, y0, z0, x1, y1, z1 = _cells(bounds, j, origin, inv_cell, dims)
        for cz in range(z0, z1 + 1):
            for cy in range(y0, y1 + 1):
                for cx in range(x0, x1 + 1):
                    c = (cz * ny + cy) * nx + cx
                    at = cursor[c]
                    items[at] = j
                    for a in range(6):
                        boxes[at, a] = bounds[j, a]
                    cursor[c] = at + 1
    return starts, items, boxes


_cells = native.inner(_cells_kernel)


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
    first,
    last,
    positions,
    rotations,
    rows,
    shape,
    size,
    large,
    origin,
    cell,
    dims,
    starts,
    items,
    boxes,
    out_shape,
    out_t,
    out_point,
    out_normal,
):
    """Rays first..last-1: the nearest shape each meets within max_t (out_shape -1: none; -2:
    the ray's origin or direction is not finite, or the direction is zero), the distance, the
    point and the normal (NaN without a hit). The large shapes first, then the grid's cells in
    the ray's order, stopping at the first cell whose exit lies past the nearest hit so far. A
    shape is tested once a ray (`seen`: the last ray that tested it), and only when the ray
    meets its bounds."""
    nx, ny, nz = dims[0], dims[1], dims[2]
    inv_cell = 1.0 / cell
    seen = np.full(len(shape), -1, np.int64)
    for k in range(first, last):
        ox, oy, oz = origins[k, 0], origins[k, 1], origins[k, 2]
        dx, dy, dz = directions[k, 0], directions[k, 1], directions[k, 2]
        length = np.sqrt(dx * dx + dy * dy + dz * dz)
        # (comparisons: fastmath's reassociation folds np.isfinite's x - x to 0)
        if not (abs(ox + oy + oz) < np.inf and 0.0 < length < np.inf):
            out_shape[k] = -2
            continue
        dx, dy, dz = dx / length, dy / length, dz / length
        ix, iy, iz = _inverse(dx), _inverse(dy), _inverse(dz)
        best, hit, hx, hy, hz = max_t, -1, 0.0, 0.0, 0.0
        for j in large:
            s0, s1, s2 = size[j, 0], size[j, 1], size[j, 2]
            t, a, b, c = shape_hit(ox, oy, oz, dx, dy, dz, positions, rotations, rows[j], shape[j], s0, s1, s2)
            if t < best or (hit < 0 and t <= best):
                best, hit, hx, hy, hz = t, j, a, b, c
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
                for m in range(starts[c0], starts[c0 + 1]):
                    if not _meets(boxes, m, ox, oy, oz, ix, iy, iz, best):
                        continue
                    j = items[m]
                    if seen[j] == k:
                        continue
                    seen[j] = k
                    s0, s1, s2 = size[j, 0], size[j, 1], size[j, 2]
                    t, a, b, c = shape_hit(ox, oy, oz, dx, dy, dz, positions, rotations, rows[j], shape[j], s0, s1, s2)
                    if t < best or (hit < 0 and t <= best):
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
        out_shape[k] = hit
        if hit < 0:
            best = hx = hy = hz = np.nan
        out_t[k] = best
        out_point[k, 0], out_point[k, 1], out_point[k, 2] = ox + dx * best, oy + dy * best, oz + dz * best
        out_normal[k, 0], out_normal[k, 1], out_normal[k, 2] = hx, hy, hz


_bounds = native.njit(_bounds_kernel)
_escaped = native.njit(_escaped_kernel)
_pose = native.njit(_pose_kernel)
_fill = native.njit(_fill_kernel)
_cast = native.njit(_cast_kernel)
AVAILABLE = _cast is not None


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two views are of the same memory (the library's buffers, viewed again)."""
    return a.shape == b.shape and a.__array_interface__["data"][0] == b.__array_interface__["data"][0]


@dataclass(frozen=True)
class Shapes:
    """The primitive shapes of a world's bodies, as long as no body is made or destroyed:
    `entity` per shape, the `rows` of their bodies in the library's buffers, their kinds and
    Collider sizes; the grid's `cell`, CELL_REACH times the median shape's reach (the diameter
    of its bounding sphere: the same however the shape turns), and which shapes are `big` (over
    LARGE_CELLS cells: tested by every ray), `small` (in the grid) and `large`."""

    entity: np.ndarray
    rows: np.ndarray
    shape: np.ndarray
    size: np.ndarray
    cell: float
    radius: np.ndarray
    big: np.ndarray
    small: np.ndarray
    large: np.ndarray

    @classmethod
    def of(cls, entity: np.ndarray, rows: np.ndarray, shape: np.ndarray, size: np.ndarray) -> Shapes:
        shape, size = np.ascontiguousarray(shape, np.int64), np.ascontiguousarray(size, np.float64)
        r, h = size[:, 0], size[:, 1]
        reach = 2.0 * np.select(
            [shape == BOX, shape == SPHERE, shape == CAPSULE],
            [np.linalg.norm(size, axis=1), r, r + h],
            np.hypot(r, h),
        )
        cell = CELL_REACH * float(np.median(reach)) if len(reach) else 1.0
        big = (reach / cell + 1.0) ** 3 > LARGE_CELLS
        rows = np.ascontiguousarray(rows, np.int64)
        return cls(entity, rows, shape, size, cell, reach / 2.0, big, np.flatnonzero(~big), np.flatnonzero(big))


@dataclass(frozen=True)
class RayGrid:
    """The shapes at one moment, and a grid of their bounds: the library's buffers they are
    posed by (`positions`, `rotations`), their `pose` when the grid was made (centres, unit
    rotations) and the `margin` their bounds were widened by; the grid from
    `origin` in cubes of `cell`, `dims` of them, whose shapes are items[starts[c]:starts[c + 1]]
    for cell c = (z * ny + y) * nx + x, their bounds boxes[starts[c]:starts[c + 1]] (low,
    then high)."""

    shapes: Shapes
    positions: np.ndarray
    rotations: np.ndarray
    pose: np.ndarray
    margin: float
    origin: np.ndarray
    cell: float
    dims: np.ndarray
    starts: np.ndarray
    items: np.ndarray
    boxes: np.ndarray

    @classmethod
    def build(cls, shapes: Shapes, positions: np.ndarray, rotations: np.ndarray) -> RayGrid:
        """The grid of `shapes` where their bodies are now (the library's buffers: positions
        (M, 4) float64, rotations (M, 4) float32), on this thread: spread over the JobPool it
        measured slower (waking the pool's threads cost more than the work saved). Where the
        shapes lie so far apart that more than CELLS_PER_SHAPE cells a shape would be needed,
        the cells are larger."""
        assert _bounds is not None and _fill is not None and _pose is not None, "the rays need numba (AVAILABLE)"
        bounds, extent = np.empty((len(shapes.entity), 6)), np.empty((2, 3))
        margin = MARGIN * shapes.cell
        _bounds(positions, rotations, shapes.rows, shapes.shape, shapes.size, shapes.big, margin, bounds, extent)
        low, high = (extent[0], extent[1]) if len(shapes.small) else (np.zeros(3), np.ones(3))
        cell = shapes.cell
        dims = np.maximum(np.ceil((high - low) / cell), 1.0)
        most = CELLS_PER_SHAPE * len(shapes.small) + 64
        if dims.prod() > most:
            cell *= float((dims.prod() / most) ** (1 / 3))
            dims = np.maximum(np.ceil((high - low) / cell), 1.0)
        dims = dims.astype(np.int64)
        starts, items, boxes = _fill(bounds, shapes.small, low, 1.0 / cell, dims)
        pose = np.empty((len(shapes.entity), 7))
        _pose(positions, rotations, shapes.rows, pose)
        return cls(shapes, positions, rotations, pose, margin, low, cell, dims, starts, items, boxes)

    def holds(self, shapes: Shapes, positions: np.ndarray, rotations: np.ndarray) -> bool:
        """Whether this grid still serves `shapes` posed as the buffers say now: the same
        shapes, and none outside the bounds the grid was made with (its margin)."""
        if shapes is not self.shapes or not (_same(positions, self.positions) and _same(rotations, self.rotations)):
            return False
        assert _escaped is not None
        s = shapes
        return not _escaped(positions, rotations, s.rows, s.big, s.radius, self.pose, self.margin)

    def cast(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        max_distance: float,
        rows: slice,
        out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    ) -> None:
        """Cast rays `rows` (origins and directions, float64, C order) into `out`: the shape
        each one hits first (an index into shapes.entity; -1: none, -2: a ray that is not
        finite or has no direction), the distance, the point and the normal."""
        s = self.shapes
        assert _cast is not None
        _cast(
            origins,
            directions,
            float(max_distance),
            rows.start,
            rows.stop,
            self.positions,
            self.rotations,
            s.rows,
            s.shape,
            s.size,
            s.large,
            self.origin,
            self.cell,
            self.dims,
            self.starts,
            self.items,
            self.boxes,
            *out,
        )
