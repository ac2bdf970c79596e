"""Temporal coherence of frustum culling (seed 004, made conservative): how long a sphere must
keep its side of the frustum, given bounds on how fast the camera and the sphere can move.

A plane of the frustum is rigid with the camera: a point `a` on it at distance L from the eye
e, unit normal n. The signed distance of a sphere's centre p is s = n.(p - a). With the eye
moving at most V (units/s), the camera turning at most W (rad/s) and the centre moving at most
v, both n and a move: |dn/dt| <= W, |da/dt . n| <= V + W L, |p - a| <= D + L with D the
centre's distance from the eye, which itself grows at most at U = V + v. So

    |ds/dt| <= U + W (D0 + 2 L) + W U t,   |s(t) - s(0)| <= f(t) = (U + W (D0 + 2L)) t + W U t^2 / 2.

A sphere of radius r is visible while s_i >= -r on every plane. A visible one stays visible at
least until f_i(t) reaches its margin s_i + r on some plane (the least such time over planes);
a culled one stays culled at least until every plane it is outside of could be crossed (the
greatest time over those planes), since it is culled while any one of them still holds it out.
The seed decremented only the head of its queue, ignored a change of speed or a turn of the
camera for visible objects and never measured its error; here every time is a bound, so a row
whose time has not run out has the state an exact test would give, provided the bounds hold
(render/culling/temporal_culling.py checks the camera's actual motion against them every frame).
"""

from __future__ import annotations

import numpy as np

NEVER = np.inf  # a sphere that nothing moves keeps its side forever


def crossing_times(margin: np.ndarray, rate: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """The least t >= 0 with rate t + accel t^2 / 2 >= margin (margin >= 0), elementwise;
    NEVER where nothing moves."""
    margin, rate, accel = np.broadcast_arrays(
        np.asarray(margin, np.float64), np.asarray(rate, np.float64), np.asarray(accel, np.float64)
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        quadratic = 2.0 * margin / (rate + np.sqrt(rate * rate + 2.0 * accel * margin))  # stable root
        out = np.where(rate > 0.0, quadratic, np.where(accel > 0.0, np.sqrt(2.0 * margin / accel), NEVER))
    return np.where(margin <= 0.0, 0.0, out)


def coherence(
    distances: np.ndarray,
    radii: np.ndarray,
    eye_distances: np.ndarray,
    plane_offsets: np.ndarray,
    move: float,
    turn: float,
    own_speed: np.ndarray | float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Per sphere: (visible now, seconds it keeps that state at least).

    distances: (n, k) signed distances of the centres to the k planes (inside positive);
    radii: (n,); eye_distances: (n,) from the eye to each centre; plane_offsets: (k,) the
    distance L of each plane from the eye (0 for a perspective frustum's side planes); move,
    turn: the camera's bounds (units/s, rad/s); own_speed: each centre's bound (units/s)."""
    s = np.asarray(distances, np.float64)
    r = np.asarray(radii, np.float64)[:, None]
    u = float(move) + np.asarray(own_speed, np.float64).reshape(-1, 1)
    rate = u + float(turn) * (np.asarray(eye_distances, np.float64)[:, None] + 2.0 * np.asarray(plane_offsets))
    accel = float(turn) * u
    margin = s + r
    inside = margin >= 0.0
    visible = inside.all(axis=1)
    times = crossing_times(np.abs(margin), rate, accel)
    keep_visible = times.min(axis=1, initial=NEVER)
    keep_culled = np.where(inside, 0.0, times).max(axis=1, initial=0.0)
    return np.asarray(visible), np.asarray(np.where(visible, keep_visible, keep_culled))
