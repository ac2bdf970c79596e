"""The compiled loops of temporal culling (temporal_culling.py), one row at a time without the
GIL: a row's sphere worked out from its model matrix as the culling kernel does, then either
its test with the time it keeps its side (maths/coherence.py's bound, the same arithmetic), or
the check that it moved no further than its speed allows. None without numba: the NumPy forms
in temporal_culling.py run then, and the tests hold the two equal."""

from __future__ import annotations

import numpy as np

from ... import native


def _sphere(model, i, centers, radii, h):  # pragma: no cover - compiled
    """Row i's sphere (centre x, y, z, radius), render-relative."""
    m = model[i]
    ex, ey, ez = centers[h, 0], centers[h, 1], centers[h, 2]
    cx = m[0, 0] * ex + m[0, 1] * ey + m[0, 2] * ez + m[0, 3]
    cy = m[1, 0] * ex + m[1, 1] * ey + m[1, 2] * ez + m[1, 3]
    cz = m[2, 0] * ex + m[2, 1] * ey + m[2, 2] * ez + m[2, 3]
    sx = m[0, 0] * m[0, 0] + m[1, 0] * m[1, 0] + m[2, 0] * m[2, 0]
    sy = m[0, 1] * m[0, 1] + m[1, 1] * m[1, 1] + m[2, 1] * m[2, 1]
    sz = m[0, 2] * m[0, 2] + m[1, 2] * m[1, 2] + m[2, 2] * m[2, 2]
    return cx, cy, cz, radii[h] * np.sqrt(max(sx, max(sy, sz)))


def _crossing(margin, rate, accel):  # pragma: no cover - compiled
    if margin <= 0.0:
        return 0.0
    if rate > 0.0:
        return 2.0 * margin / (rate + np.sqrt(rate * rate + 2.0 * accel * margin))
    if accel > 0.0:
        return np.sqrt(2.0 * margin / accel)
    return np.inf


def _retest_kernel(
    rows, model, handle, centers, radii, planes, offsets, eye, move, turn, linear, angular, slack, out
):  # pragma: no cover - compiled
    """Test `rows`: out[k] = (cx, cy, cz, r, own speed, visible, seconds kept) of rows[k]."""
    for k in range(rows.shape[0]):
        i = rows[k]
        h = handle[i]
        cx, cy, cz, r = _sphere(model, i, centers, radii, h)
        speed = 0.0
        if linear.shape[0] > 0:
            speed += np.sqrt(linear[i, 0] ** 2 + linear[i, 1] ** 2 + linear[i, 2] ** 2)
        if angular.shape[0] > 0:
            ox, oy, oz = cx - model[i, 0, 3], cy - model[i, 1, 3], cz - model[i, 2, 3]
            spin = np.sqrt(angular[i, 0] ** 2 + angular[i, 1] ** 2 + angular[i, 2] ** 2)
            speed += spin * np.sqrt(ox * ox + oy * oy + oz * oz)
        big = max(abs(cx), max(abs(cy), abs(cz)))
        r_test = r * (1.0 + slack) + slack * (1.0 + big)  # never cull what the exact test keeps
        far = np.sqrt((cx - eye[0]) ** 2 + (cy - eye[1]) ** 2 + (cz - eye[2]) ** 2)
        u = move + speed
        accel = turn * u
        visible = True
        keep_visible = np.inf
        keep_culled = 0.0
        for p in range(planes.shape[0]):
            margin = planes[p, 0] * cx + planes[p, 1] * cy + planes[p, 2] * cz + planes[p, 3] + r_test
            t = _crossing(abs(margin), u + turn * (far + 2.0 * offsets[p]), accel)
            if margin >= 0.0:
                keep_visible = min(keep_visible, t)
            else:
                visible = False
                keep_culled = max(keep_culled, t)
        out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4] = cx, cy, cz, r, speed
        out[k, 5] = 1.0 if visible else 0.0
        out[k, 6] = keep_visible if visible else keep_culled


def _moved_kernel(
    model, handle, centers, radii, origin, center0, radius0, speed, tested, now, slack, out
):  # pragma: no cover - compiled
    """out[i]: row i's sphere moved further from center0 (world) than speed * time allows, or
    changed size."""
    for i in range(handle.shape[0]):
        cx, cy, cz, r = _sphere(model, i, centers, radii, handle[i])
        dx = cx + origin[0] - center0[i, 0]
        dy = cy + origin[1] - center0[i, 1]
        dz = cz + origin[2] - center0[i, 2]
        big = max(abs(cx), max(abs(cy), abs(cz)))
        allowed = speed[i] * (now - tested[i]) + slack * (1.0 + big)
        out[i] = dx * dx + dy * dy + dz * dz > allowed * allowed or abs(r - radius0[i]) > slack * (1.0 + r)


_sphere = native.inner(_sphere)
_crossing = native.inner(_crossing)
retest_native = native.njit(_retest_kernel)
moved_native = native.njit(_moved_kernel)
