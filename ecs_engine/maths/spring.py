"""Steps of a damped spring, x'' = -(k/m)(x - anchor) - (c/m) x', vectorised over rows.

Five integrators, the cheap and unstable to the exact:
- `explicit`: explicit Euler. Grows without bound for any undamped spring; unstable once
  k dt^2 / m passes about 4 even with damping.
- `semi_implicit`: symplectic Euler (velocity first, then position with the new velocity). Energy
  stays bounded while omega dt < 2 (omega = sqrt(k/m)); beyond that it explodes.
- `implicit`: backward Euler, solved in closed form (the spring is linear). Stable for every
  dt; it damps more than the real spring does.
- `rk4`: classic Runge-Kutta. Fourth-order accurate; unstable once omega dt passes about 2.8.
- `exact`: the analytic solution over one step (the 2x2 matrix exponential), for constant
  k, c, m and anchor within the step. Stable and exact for any dt, and dearer per step.

Every function updates `x` and `v` (n, 3) in place. k, c, m are (n,) arrays or scalars.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

Coefficient = np.ndarray | float  # per spring (n,) or one for all

INTEGRATORS = ("explicit", "semi_implicit", "implicit", "rk4", "exact")


def _col(a: Coefficient) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    return a[:, None] if a.ndim == 1 else a


def explicit(
    x: np.ndarray, v: np.ndarray, anchor: np.ndarray, k: Coefficient, c: Coefficient, m: Coefficient, dt: float
) -> None:
    kk, cc, mm = _col(k), _col(c), _col(m)
    a = (-kk * (x - anchor) - cc * v) / mm
    x += v * dt
    v += a * dt


def semi_implicit(
    x: np.ndarray, v: np.ndarray, anchor: np.ndarray, k: Coefficient, c: Coefficient, m: Coefficient, dt: float
) -> None:
    kk, cc, mm = _col(k), _col(c), _col(m)
    v += (-kk * (x - anchor) - cc * v) / mm * dt
    x += v * dt


def implicit(
    x: np.ndarray, v: np.ndarray, anchor: np.ndarray, k: Coefficient, c: Coefficient, m: Coefficient, dt: float
) -> None:
    """v1 = v0 + dt a(x1, v1), x1 = x0 + dt v1, solved for v1 (one division per row)."""
    kk, cc, mm = _col(k), _col(c), _col(m)
    v[...] = (v - dt * kk / mm * (x - anchor)) / (1.0 + dt * cc / mm + dt * dt * kk / mm)
    x += v * dt


def rk4(
    x: np.ndarray, v: np.ndarray, anchor: np.ndarray, k: Coefficient, c: Coefficient, m: Coefficient, dt: float
) -> None:
    kk, cc, mm = _col(k), _col(c), _col(m)

    def acc(xx: np.ndarray, vv: np.ndarray) -> np.ndarray:
        return (-kk * (xx - anchor) - cc * vv) / mm

    a1 = acc(x, v)
    x2, v2 = x + 0.5 * dt * v, v + 0.5 * dt * a1
    a2 = acc(x2, v2)
    x3, v3 = x + 0.5 * dt * v2, v + 0.5 * dt * a2
    a3 = acc(x3, v3)
    x4, v4 = x + dt * v3, v + dt * a3
    a4 = acc(x4, v4)
    x += dt / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4)
    v += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)


def exact_coefficients(
    k: Coefficient, c: Coefficient, m: Coefficient, dt: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """exp(M dt) for M = [[0, 1], [-w2, -b]] (w2 = k/m, b = c/m), as (p00, p01, p10, p11):
    x1 - anchor = p00 (x0 - anchor) + p01 v0, v1 = p10 (x0 - anchor) + p11 v0.

    exp(M t) = e^(-b t/2) (C I + S (M + b/2 I)) with s^2 = b^2/4 - w2; C = cosh(s t),
    S = sinh(s t)/s when s^2 > 0 (overdamped), C = cos(w t), S = sin(w t)/w with w^2 = -s^2
    when underdamped, and C = 1, S = t when critically damped."""
    w2 = np.atleast_1d(np.asarray(k, dtype=np.float64) / np.asarray(m, dtype=np.float64))
    b = np.atleast_1d(np.asarray(c, dtype=np.float64) / np.asarray(m, dtype=np.float64))
    w2, b = np.broadcast_arrays(w2, b)
    s2 = b * b / 4.0 - w2
    t = float(dt)
    root = np.sqrt(np.abs(s2))
    st = root * t
    with np.errstate(over="ignore", invalid="ignore"):
        over = s2 > 1e-12 * np.maximum(w2, 1e-300)
        under = s2 < -1e-12 * np.maximum(w2, 1e-300)
        # overdamped: e^(-bt/2) cosh(st) etc. computed as sums of two decaying exponentials
        # so huge b t does not overflow: e^(-bt/2 + st) and e^(-bt/2 - st)
        e_plus = np.exp(-b * t / 2.0 + st)
        e_minus = np.exp(-b * t / 2.0 - st)
        c_over = 0.5 * (e_plus + e_minus)
        s_over = np.where(root > 0, 0.5 * (e_plus - e_minus) / np.where(root > 0, root, 1.0), 0.0)
        decay = np.exp(-b * t / 2.0)
        c_under = decay * np.cos(st)
        s_under = decay * np.where(root > 0, np.sin(st) / np.where(root > 0, root, 1.0), t)
        c_crit = decay
        s_crit = decay * t
    cc = np.where(over, c_over, np.where(under, c_under, c_crit))
    ss = np.where(over, s_over, np.where(under, s_under, s_crit))
    # C I + S (M + b/2 I), both already scaled by the decay
    p00 = cc + ss * (b / 2.0)
    p01 = ss
    p10 = -ss * w2
    p11 = cc + ss * (-b + b / 2.0)
    return p00, p01, p10, p11


def exact(
    x: np.ndarray, v: np.ndarray, anchor: np.ndarray, k: Coefficient, c: Coefficient, m: Coefficient, dt: float
) -> None:
    p00, p01, p10, p11 = (_col(p) for p in exact_coefficients(k, c, m, dt))
    d = x - anchor
    x[...] = anchor + p00 * d + p01 * v
    v[...] = p10 * d + p11 * v


STEPS: dict[str, Callable[..., None]] = {
    "explicit": explicit,
    "semi_implicit": semi_implicit,
    "implicit": implicit,
    "rk4": rk4,
    "exact": exact,
}


def step(
    integrator: str,
    x: np.ndarray,
    v: np.ndarray,
    anchor: np.ndarray,
    k: Coefficient,
    c: Coefficient,
    m: Coefficient,
    dt: float,
) -> None:
    try:
        fn = STEPS[integrator]
    except KeyError:
        raise ValueError(f"unknown integrator {integrator!r}; integrators: {', '.join(INTEGRATORS)}") from None
    fn(x, v, anchor, k, c, m, dt)
