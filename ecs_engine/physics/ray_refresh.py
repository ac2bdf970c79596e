"""The grid of the engine's rays (ray_grid.py) brought up to the step: the shapes that moved
further than the grid's margin since they were put in their cells are found, and moved into
the cells their bounds cover now. A shape that leaves the grid's box or finds a cell full is
tested by every ray instead, up to SPILL of them; past that the grid is made again.

Before the rays are cast, on this thread or, for many rays, on numba's threads in the kernel
that casts them (ray_spread.py): they share the look at every shape, then one of them moves the
escaped shapes, in the order of their index, while the others wait."""

from __future__ import annotations

import numpy as np

from .. import native
from ..native import fetch_add
from .poses import pose_rows
from .ray_bounds import bound, cells, insert, take

SPILL = 32  # shapes at most outside the grid's cells, tested by every ray (by their bounds first)


def _moved_kernel(positions, rotations, r, centre, turn, i, radius):  # pragma: no cover
    """How far any point of shape i (its body at row r, its bounding sphere's `radius`) may
    have moved since it was at centre[i], turned by the unit quaternion turn[i]: its centre's
    move plus its radius times the turn's chord, 2 |q - q0| for unit quaternions on the same
    side."""
    dx, dy, dz = positions[r, 0] - centre[i, 0], positions[r, 1] - centre[i, 1], positions[r, 2] - centre[i, 2]
    x, y = np.float64(rotations[r, 0]), np.float64(rotations[r, 1])
    z, w = np.float64(rotations[r, 2]), np.float64(rotations[r, 3])
    inv = 1.0 / np.sqrt(x * x + y * y + z * z + w * w)
    if x * turn[i, 0] + y * turn[i, 1] + z * turn[i, 2] + w * turn[i, 3] < 0.0:
        inv = -inv
    qx, qy, qz, qw = x * inv - turn[i, 0], y * inv - turn[i, 1], z * inv - turn[i, 2], w * inv - turn[i, 3]
    return np.sqrt(dx * dx + dy * dy + dz * dz) + 2.0 * radius * np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)


_moved = native.inner(_moved_kernel)


def _move_kernel(
    escaped, positions, rotations, rows, shape, size, margin, centre, turn, bounds, layout, spill
):  # pragma: no cover
    """Each escaped shape taken out of its cells and put into those its bounds (`margin` wide)
    cover now, its pose there noted in centre and turn. One that leaves the grid's box, or
    finds a cell full, goes to the `spill` (its count, then the shapes: every ray tests them,
    by their bounds first); a cell it did fit in keeps it (a ray looks at a shape once). False
    where the spill is full: the grid is then half moved, to be made again."""
    origin, cell, dims, starts, fill, items, boxes = layout
    for n in range(len(escaped)):
        j = escaped[n]
        for m in range(1, spill[0] + 1):
            if spill[m] == j:  # (the last takes its place)
                spill[m] = spill[spill[0]]
                spill[0] -= 1
                break
        x0, y0, z0, x1, y1, z1 = cells(bounds, j, origin, 1.0 / cell, dims)
        for cz in range(z0, z1 + 1):
            for cy in range(y0, y1 + 1):
                for cx in range(x0, x1 + 1):
                    c = (cz * dims[1] + cy) * dims[0] + cx
                    last = starts[c] + fill[c] - 1
                    for m in range(starts[c], last + 1):
                        if items[m] == j:  # the cell's last item takes its place
                            items[m] = items[last]
                            for a in range(6):
                                boxes[m, a] = boxes[last, a]
                            fill[c] -= 1
                            break
        r = rows[j]
        bound(positions, rotations, r, shape[j], size[j, 0], size[j, 1], size[j, 2], margin, bounds, j)
        inside = True
        for a in range(3):
            if bounds[j, a] < origin[a] or bounds[j, 3 + a] > origin[a] + dims[a] * cell:
                inside = False
        if not (inside and insert(layout, bounds, j, False)):
            if spill[0] == len(spill) - 1:
                return False
            spill[0] += 1
            spill[spill[0]] = j
    pose_rows(positions, rotations, rows[escaped], escaped, centre, turn)  # where they were put
    return True


_move = native.inner(_move_kernel)


LOOK_BLOCK = 512  # shapes a thread looks at at a time


def _look_kernel(claims, positions, rotations, rows, looked, radius, margin, centre, turn, marks):  # pragma: no cover
    """The `looked` shapes that moved further than the margin, in blocks taken from claims[0]
    (by the threads looking, or one): marked (marks[i] 1), claims[1] counting them; claims[2]
    counts the shapes looked at."""
    while True:
        first, last = take(claims, 0, LOOK_BLOCK, len(looked))
        if first == last:
            break
        for k in range(first, last):
            i = looked[k]
            if _moved(positions, rotations, rows[i], centre, turn, i, radius[i]) > margin:
                marks[i] = 1
                fetch_add(claims, 1, 1)
        fetch_add(claims, 2, last - first)


look = native.inner(_look_kernel)


def _settle_kernel(
    claims, looked, marks, positions, rotations, rows, shape, size, margin, centre, turn, bounds, layout, spill
):  # pragma: no cover
    """The marked shapes (claims[1] of them) moved, in the order of their index (whichever
    threads marked them), their marks cleared: whether the grid holds every shape now."""
    if claims[1] == 0:
        return True
    found, n = np.empty(claims[1], np.int64), 0
    for k in range(len(looked)):
        i = looked[k]
        if marks[i]:
            marks[i] = 0
            found[n] = i
            n += 1
    return _move(found, positions, rotations, rows, shape, size, margin, centre, turn, bounds, layout, spill)


settle = native.inner(_settle_kernel)


def _refresh_kernel(claims, shapes, move):  # pragma: no cover
    """The grid brought up to the step (the module's docstring) on this thread: look with
    `shapes`' arguments, settle with `move`'s: whether it holds every shape now (False: it is
    to be made again)."""
    look(claims, *shapes)
    return settle(claims, shapes[3], shapes[-1], *move)


def counters() -> np.ndarray:
    """A refresh's counters (_look's three, then the fused kernel's in ray_spread.py)."""
    return np.zeros(5, np.int64)


refresh = native.njit(_refresh_kernel)
