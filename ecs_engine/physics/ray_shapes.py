"""Where a ray first meets a box, a sphere, a capsule or a cylinder (a Collider's primitive
shapes, sized as it sizes them), in the shape's own frame and then in the world's: compiled
helpers of the engine's ray casts (ray_grid.py), exact as the library's are, in float64."""

from __future__ import annotations

import numpy as np

from .. import native
from ..components.physics import BOX, CAPSULE, SPHERE


def _sphere_kernel(lx, ly, lz, ux, uy, uz, r):  # pragma: no cover
    """A ray from l along unit u against a sphere of radius r at the origin: (t, local normal);
    t = inf: it misses, t < 0: it starts inside."""
    b, c = lx * ux + ly * uy + lz * uz, lx * lx + ly * ly + lz * lz - r * r
    if c <= 0.0:
        return -1.0, 0.0, 0.0, 0.0
    disc = b * b - c
    if disc < 0.0 or b > 0.0:
        return np.inf, 0.0, 0.0, 0.0
    t = -b - np.sqrt(disc)
    return t, (lx + ux * t) / r, (ly + uy * t) / r, (lz + uz * t) / r


def _capsule_kernel(lx, ly, lz, ux, uy, uz, r, h):  # pragma: no cover
    """Likewise against a capsule about y (radius r, half height h): the first of its side and
    its two end spheres, or inside when the start is within r of the axis segment."""
    cy = min(max(ly, -h), h)
    if lx * lx + (ly - cy) * (ly - cy) + lz * lz <= r * r:
        return -1.0, 0.0, 0.0, 0.0
    best, nx, ny, nz = np.inf, 0.0, 0.0, 0.0
    a2 = ux * ux + uz * uz
    if a2 > 1e-300:
        b, c = lx * ux + lz * uz, lx * lx + lz * lz - r * r
        disc = b * b - a2 * c
        if disc >= 0.0:
            t = (-b - np.sqrt(disc)) / a2
            if t >= 0.0 and abs(ly + uy * t) <= h:
                best, nx, ny, nz = t, (lx + ux * t) / r, 0.0, (lz + uz * t) / r
    for end in (-h, h):
        t, ex, ey, ez = _sphere(lx, ly - end, lz, ux, uy, uz, r)
        if 0.0 <= t < best:
            best, nx, ny, nz = t, ex, ey, ez
    return best, nx, ny, nz


def _slab_kernel(o, u, half, enter, leave):  # pragma: no cover
    """(enter, leave) met with the ray's span in the slab |x| <= half (o: where it starts, u: its
    step along x), and whether the slab set enter. leave < enter: it misses."""
    if abs(u) < 1e-300:
        return enter, (leave if abs(o) <= half else -np.inf), False
    t1, t2 = (-half - o) / u, (half - o) / u
    if t1 > t2:
        t1, t2 = t2, t1
    return max(enter, t1), min(leave, t2), t1 > enter


def _box_kernel(lx, ly, lz, ux, uy, uz, hx, hy, hz):  # pragma: no cover
    """Likewise against a box of half extents h: the meet of three slabs, entered at the last
    entry (the normal is that slab's), left at the first exit."""
    enter, leave, _ = _slab(lx, ux, hx, -np.inf, np.inf)
    enter, leave, fy = _slab(ly, uy, hy, enter, leave)
    enter, leave, fz = _slab(lz, uz, hz, enter, leave)
    if leave < max(enter, 0.0):
        return np.inf, 0.0, 0.0, 0.0
    if enter < 0.0:
        return -1.0, 0.0, 0.0, 0.0
    if fz:
        return enter, 0.0, 0.0, (-1.0 if uz > 0.0 else 1.0)
    if fy:
        return enter, 0.0, (-1.0 if uy > 0.0 else 1.0), 0.0
    return enter, (-1.0 if ux > 0.0 else 1.0), 0.0, 0.0


def _cylinder_kernel(lx, ly, lz, ux, uy, uz, r, h):  # pragma: no cover
    """Likewise against a cylinder about y (radius r, half height h): the slab |y| <= h met with
    the infinite cylinder."""
    enter, leave, _ = _slab(ly, uy, h, -np.inf, np.inf)
    nx, ny, nz = 0.0, (-1.0 if uy > 0.0 else 1.0), 0.0
    a2 = ux * ux + uz * uz
    if a2 < 1e-300:
        if lx * lx + lz * lz > r * r:
            return np.inf, 0.0, 0.0, 0.0
    else:
        b, c = lx * ux + lz * uz, lx * lx + lz * lz - r * r
        disc = b * b - a2 * c
        if disc < 0.0:
            return np.inf, 0.0, 0.0, 0.0
        root = np.sqrt(disc)
        t1 = (-b - root) / a2
        if t1 > enter:
            enter, nx, ny, nz = t1, (lx + ux * t1) / r, 0.0, (lz + uz * t1) / r
        leave = min(leave, (-b + root) / a2)
    if leave < max(enter, 0.0):
        return np.inf, 0.0, 0.0, 0.0
    if enter < 0.0:
        return -1.0, 0.0, 0.0, 0.0
    return enter, nx, ny, nz


_slab = native.inner(_slab_kernel)
_sphere = native.inner(_sphere_kernel)
_capsule = native.inner(_capsule_kernel)
_box = native.inner(_box_kernel)
_cylinder = native.inner(_cylinder_kernel)


def _turn_at_kernel(rotations, r):  # pragma: no cover
    """The rotation matrix, row by row, of the quaternion at row r of the library's buffer
    (x, y, z, w, float32), made unit."""
    x, y = np.float64(rotations[r, 0]), np.float64(rotations[r, 1])
    z, w = np.float64(rotations[r, 2]), np.float64(rotations[r, 3])
    inv = 2.0 / (x * x + y * y + z * z + w * w)
    return (
        1 - (y * y + z * z) * inv, (x * y - z * w) * inv, (x * z + y * w) * inv,
        (x * y + z * w) * inv, 1 - (x * x + z * z) * inv, (y * z - x * w) * inv,
        (x * z - y * w) * inv, (y * z + x * w) * inv, 1 - (x * x + y * y) * inv,
    )  # fmt: skip


turn_at = native.inner(_turn_at_kernel)


def _shape_hit_kernel(ox, oy, oz, dx, dy, dz, positions, rotations, row, kind, s0, s1, s2):  # pragma: no cover
    """Where the ray (from o along unit d) first meets a shape of `kind` and Collider sizes s,
    posed as the body at `row` of the library's buffers: (t, world normal); t = inf when it
    misses, 0 when it starts inside (the normal then against the ray)."""
    m0, m1, m2, m3, m4, m5, m6, m7, m8 = turn_at(rotations, row)
    px, py, pz = ox - positions[row, 0], oy - positions[row, 1], oz - positions[row, 2]
    # into the shape's frame: the rotation transposed
    lx, ly, lz = m0 * px + m3 * py + m6 * pz, m1 * px + m4 * py + m7 * pz, m2 * px + m5 * py + m8 * pz
    ux, uy, uz = m0 * dx + m3 * dy + m6 * dz, m1 * dx + m4 * dy + m7 * dz, m2 * dx + m5 * dy + m8 * dz
    if kind == SPHERE:
        t, nx, ny, nz = _sphere(lx, ly, lz, ux, uy, uz, s0)
    elif kind == CAPSULE:
        t, nx, ny, nz = _capsule(lx, ly, lz, ux, uy, uz, s0, s1)
    elif kind == BOX:
        t, nx, ny, nz = _box(lx, ly, lz, ux, uy, uz, s0, s1, s2)
    else:
        t, nx, ny, nz = _cylinder(lx, ly, lz, ux, uy, uz, s0, s1)
    if t < 0.0:
        return 0.0, -dx, -dy, -dz
    return t, m0 * nx + m1 * ny + m2 * nz, m3 * nx + m4 * ny + m5 * nz, m6 * nx + m7 * ny + m8 * nz


shape_hit = native.inner(_shape_hit_kernel)
