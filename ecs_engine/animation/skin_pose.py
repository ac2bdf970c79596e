"""A skin's copies posed in one pass: each joint's matrix (its world matrix times its inverse
bind matrix) as the three float32 rows the vertex shader reads, relative to the render origin
(as ModelMatrix is), and a sphere around each copy's posed vertices. A numba kernel over copies
(threads take ranges of copies) and its NumPy reference; skins.py calls them.

The sphere: a vertex moved by joint j alone lies within reach_j times the joint's largest axis
scale of the joint's origin, and a vertex several joints move lies in the hull of those balls;
the sphere holds the box around the balls."""

from __future__ import annotations

import numpy as np

from .. import native


def pose_numpy(
    worlds: np.ndarray, rows: np.ndarray, binds: np.ndarray, reach: np.ndarray, origin: np.ndarray,
    out: np.ndarray, centres: np.ndarray, radii: np.ndarray, start: int, stop: int,
) -> None:  # fmt: skip
    """Reference version of `pose`."""
    r = rows[start:stop]
    w = np.where((r >= 0)[..., None, None], worlds[np.maximum(r, 0)], np.eye(4))
    m = w @ binds
    m[..., :3, 3] -= origin
    out[start:stop] = m[..., :3, :]
    at = w[..., :3, 3]
    ball = reach * np.sqrt((w[..., :3, :3] ** 2).sum(axis=-2)).max(axis=-1)
    low, high = (at - ball[..., None]).min(axis=1), (at + ball[..., None]).max(axis=1)
    centres[start:stop] = (low + high) / 2
    radii[start:stop] = (np.sqrt(((at - centres[start:stop, None]) ** 2).sum(axis=2)) + ball).max(axis=1)


def _pose_kernel(worlds, rows, binds, reach, origin, out, centres, radii, start, stop):  # pragma: no cover - compiled
    joints = binds.shape[0]
    balls = np.empty((joints, 4))
    for c in range(start, stop):
        lo0, lo1, lo2 = np.inf, np.inf, np.inf
        hi0, hi1, hi2 = -np.inf, -np.inf, -np.inf
        for j in range(joints):
            r = rows[c, j]
            for i in range(3):
                if r >= 0:
                    w0, w1, w2, w3 = worlds[r, i, 0], worlds[r, i, 1], worlds[r, i, 2], worlds[r, i, 3]
                else:  # a joint that is gone: the identity
                    w0, w1, w2, w3 = 1.0 if i == 0 else 0.0, 1.0 if i == 1 else 0.0, 1.0 if i == 2 else 0.0, 0.0
                for k in range(4):
                    v = w0 * binds[j, 0, k] + w1 * binds[j, 1, k] + w2 * binds[j, 2, k] + w3 * binds[j, 3, k]
                    out[c, j, i, k] = v - origin[i] if k == 3 else v
            if r >= 0:
                x, y, z = worlds[r, 0, 3], worlds[r, 1, 3], worlds[r, 2, 3]
                scale = 0.0
                for k in range(3):
                    a, b, d = worlds[r, 0, k], worlds[r, 1, k], worlds[r, 2, k]
                    scale = max(scale, a * a + b * b + d * d)
                ball = reach[j] * np.sqrt(scale)
            else:
                x, y, z, ball = 0.0, 0.0, 0.0, reach[j]
            balls[j, 0], balls[j, 1], balls[j, 2], balls[j, 3] = x, y, z, ball
            lo0, lo1, lo2 = min(lo0, x - ball), min(lo1, y - ball), min(lo2, z - ball)
            hi0, hi1, hi2 = max(hi0, x + ball), max(hi1, y + ball), max(hi2, z + ball)
        cx, cy, cz = (lo0 + hi0) / 2, (lo1 + hi1) / 2, (lo2 + hi2) / 2
        radius = 0.0
        for j in range(joints):
            dx, dy, dz = balls[j, 0] - cx, balls[j, 1] - cy, balls[j, 2] - cz
            radius = max(radius, np.sqrt(dx * dx + dy * dy + dz * dz) + balls[j, 3])
        centres[c, 0], centres[c, 1], centres[c, 2] = cx, cy, cz
        radii[c] = radius


_pose_native = native.njit(_pose_kernel)


def pose(
    worlds: np.ndarray, rows: np.ndarray, binds: np.ndarray, reach: np.ndarray, origin: np.ndarray,
    out: np.ndarray, centres: np.ndarray, radii: np.ndarray, start: int, stop: int,
) -> None:  # fmt: skip
    """Copies start:stop of a skin: `worlds` (T, 4, 4) float64 holds the joints' world matrices at
    `rows` (copies, J; -1: a joint that is gone, the identity); `binds` (J, 4, 4), `reach` (J,);
    into `out` (copies, J, 3, 4) float32 (translations less `origin`), `centres` (copies, 3) and
    `radii` (copies,). Releases the GIL with numba."""
    if _pose_native is None:
        pose_numpy(worlds, rows, binds, reach, origin, out, centres, radii, start, stop)
        return
    _pose_native(worlds, rows, binds, reach, origin, out, centres, radii, start, stop)


def place_numpy(
    skin: np.ndarray, copy: np.ndarray, radius: np.ndarray, centre: np.ndarray, first: np.ndarray,
    centres: np.ndarray, radii: np.ndarray, origin: np.ndarray, model: np.ndarray,
) -> None:  # fmt: skip
    """Reference version of `place`."""
    known = (skin >= 0) & (skin < len(first) - 1)
    at = first[np.where(known, skin, 0)] + copy
    known &= at < first[np.where(known, skin, 0) + 1]
    rows = np.flatnonzero(known)
    scale = radii[at[rows]] / np.maximum(radius[rows].astype(np.float64), 1e-30)
    m = np.zeros((len(rows), 4, 4))
    m[:, [0, 1, 2], [0, 1, 2]] = scale[:, None]
    m[:, :3, 3] = centres[at[rows]] - origin - scale[:, None] * centre[rows]
    m[:, 3, 3] = 1.0
    model[rows] = m


def _place_kernel(skin, copy, radius, centre, first, centres, radii, origin, model):  # pragma: no cover - compiled
    skins = first.shape[0] - 1
    for i in range(skin.shape[0]):
        s = skin[i]
        if s < 0 or s >= skins:
            continue
        at = first[s] + copy[i]
        if at >= first[s + 1]:
            continue
        scale = radii[at] / max(np.float64(radius[i]), 1e-30)
        for r in range(4):
            for c in range(4):
                model[i, r, c] = 0.0
        for r in range(3):
            model[i, r, r] = scale
            model[i, r, 3] = centres[at, r] - origin[r] - scale * centre[i, r]
        model[i, 3, 3] = 1.0


_place_native = native.njit(_place_kernel)


def place(
    skin: np.ndarray, copy: np.ndarray, radius: np.ndarray, centre: np.ndarray, first: np.ndarray,
    centres: np.ndarray, radii: np.ndarray, origin: np.ndarray, model: np.ndarray,
) -> None:  # fmt: skip
    """Each Skinned row's ModelMatrix (`model`, float32): its mesh's sphere (`centre`, `radius`)
    scaled and moved onto its copy's pose sphere, less `origin`. `skin`, `copy` per row; `first`
    (skins + 1) the first copy of each skin in `centres` and `radii`, all skins' copies in turn.
    Rows naming no skin or copy are left."""
    if _place_native is None:
        place_numpy(skin, copy, radius, centre, first, centres, radii, origin, model)
        return
    _place_native(skin, copy, radius, centre, first, centres, radii, origin, model)
