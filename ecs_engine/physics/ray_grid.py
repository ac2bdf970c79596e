"""Rays against the bodies' primitive shapes (boxes, spheres, capsules, cylinders), cast by the
engine in compiled loops that release the GIL, over a uniform grid of the shapes' bounds.

Why not the library's batch: culverin's reads each hit's body through Jolt's locking body
interface, so its threads contend: 10,000 rays on a pile of 10,000 boxes took 4.0-4.3 ms on 16
threads of the GPU host, these 1.25-1.31 (a median step; docs/physics.md). The primitives'
poses are in the library's shared buffers already. A grid of their bounds, a little wide, is
made from them and kept from step to step until a shape moves further than that margin; each
ray walks it cell by cell (ray_walk.py), testing a shape's bounds and then its exact shape
(ray_shapes.py), as the library does, in float64. Shapes too big for the grid's cells (a
floor) are tested by every ray."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import native
from ..components.physics import BOX, CAPSULE, SPHERE
from .poses import copy_poses
from .ray_shapes import turn_at
from .ray_walk import cast_rays

CELL_REACH = 0.7  # the grid's cell, in the median shape's reach (its bounding sphere's diameter)
MARGIN = 0.02  # the shapes' bounds in the grid are this many cells wider all round: the grid
# stands for the steps after it was made until a shape moves further than that
LARGE_CELLS = 64  # a shape over more cells than this is tested by every ray instead
CELLS_PER_SHAPE = 4  # the grid has at most this many cells per shape (more for far-apart shapes)


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


def _bounds_kernel(positions, rotations, rows, shape, size, big, margin, bounds, extent):  # pragma: no cover
    """Each shape's world bounds from the buffers, `margin` wider all round (bounds: low x y z,
    high x y z), and `extent`, the bounds of the shapes that are not `big` (low, then
    high)."""
    extent[0, :], extent[1, :] = np.inf, -np.inf
    for i in range(len(rows)):
        r = rows[i]
        reach = _reach(rotations, r, shape[i], size[i, 0], size[i, 1], size[i, 2])
        for a in range(3):
            c = positions[r, a]
            e = reach[a] + margin + 1e-6 * abs(c)
            bounds[i, a], bounds[i, 3 + a] = c - e, c + e
            if not big[i]:
                extent[0, a], extent[1, a] = min(extent[0, a], c - e), max(extent[1, a], c + e)


def _escaped_kernel(positions, rotations, rows, big, radius, centre, turn, margin):  # pragma: no cover
    """Whether any shape that is not `big` may reach outside the bounds the grid was made with
    (`margin` wider than it was at `centre`, turned by the unit quaternion `turn`). No point of
    a shape has moved further than its centre has plus its radius times the turn's chord,
    2 |q - q0| for unit quaternions on the same side; while that stays within the margin the
    grid holds every shape in its cells."""
    for i in range(len(rows)):
        if big[i]:
            continue
        r = rows[i]
        dx, dy, dz = positions[r, 0] - centre[i, 0], positions[r, 1] - centre[i, 1], positions[r, 2] - centre[i, 2]
        x, y = np.float64(rotations[r, 0]), np.float64(rotations[r, 1])
        z, w = np.float64(rotations[r, 2]), np.float64(rotations[r, 3])
        inv = 1.0 / np.sqrt(x * x + y * y + z * z + w * w)
        if x * turn[i, 0] + y * turn[i, 1] + z * turn[i, 2] + w * turn[i, 3] < 0.0:
            inv = -inv
        qx, qy, qz, qw = x * inv - turn[i, 0], y * inv - turn[i, 1], z * inv - turn[i, 2], w * inv - turn[i, 3]
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


_bounds = native.njit(_bounds_kernel)
_escaped = native.njit(_escaped_kernel)
_fill = native.njit(_fill_kernel)
AVAILABLE = cast_rays is not None


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
    posed by (`positions`, `rotations`), their `centre` and `turn` when the grid was made (unit
    rotations) and the `margin` their bounds were widened by; the grid from
    `origin` in cubes of `cell`, `dims` of them, whose shapes are items[starts[c]:starts[c + 1]]
    for cell c = (z * ny + y) * nx + x, their bounds boxes[starts[c]:starts[c + 1]] (low,
    then high)."""

    shapes: Shapes
    positions: np.ndarray
    rotations: np.ndarray
    centre: np.ndarray
    turn: np.ndarray
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
        assert _bounds is not None and _fill is not None, "the engine's rays need numba (ray_grid.AVAILABLE)"
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
        centre, turn = np.empty((len(shapes.entity), 3)), np.empty((len(shapes.entity), 4))
        copy_poses(positions, rotations, shapes.rows, np.arange(len(shapes.entity)), centre, turn)
        return cls(shapes, positions, rotations, centre, turn, margin, low, cell, dims, starts, items, boxes)

    def holds(self, shapes: Shapes, positions: np.ndarray, rotations: np.ndarray) -> bool:
        """Whether this grid still serves `shapes` posed as the buffers say now: the same
        shapes, and none outside the bounds the grid was made with (its margin)."""
        if shapes is not self.shapes or not (_same(positions, self.positions) and _same(rotations, self.rotations)):
            return False
        assert _escaped is not None
        s = shapes
        return not _escaped(positions, rotations, s.rows, s.big, s.radius, self.centre, self.turn, self.margin)

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
        assert cast_rays is not None
        cast_rays(
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
