"""Vectorised transform maths over component columns (NumPy reference and numba kernels).

Conventions: quaternions are (x, y, z, w); matrices are indexed [row, column] and multiply
column vectors (p' = M @ p); the shaders declare them row_major. Model matrices are
camera-relative: the translation is (position - origin), subtracted in float64 before the
cast to float32, so a scene far from the origin keeps its precision.

Normal matrices are the cofactor of the model's 3x3 part (R * diag(sy*sz, sx*sz, sx*sy)),
sign-corrected for mirroring and scaled so the largest column is 1. Unlike the inverse
transpose this stays finite for zero scale (a flattened axis gets a zero column, the shader
normalises what is left) and does not overflow for huge scales.
"""

from __future__ import annotations

import numpy as np

from . import native


def quat_to_mat3(q: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions -> (n, 3, 3) rotation matrices; non-unit input is normalised."""
    x, y, z, w = (q[:, i] for i in range(4))
    n2 = x * x + y * y + z * z + w * w
    s = np.divide(2.0, n2, out=np.zeros_like(n2), where=n2 > 0)
    out = np.empty((len(q), 3, 3), dtype=np.float64)
    out[:, 0, 0] = 1 - s * (y * y + z * z)
    out[:, 0, 1] = s * (x * y - z * w)
    out[:, 0, 2] = s * (x * z + y * w)
    out[:, 1, 0] = s * (x * y + z * w)
    out[:, 1, 1] = 1 - s * (x * x + z * z)
    out[:, 1, 2] = s * (y * z - x * w)
    out[:, 2, 0] = s * (x * z - y * w)
    out[:, 2, 1] = s * (y * z + x * w)
    out[:, 2, 2] = 1 - s * (x * x + y * y)
    return out


def normal_scale(scale: np.ndarray) -> np.ndarray:
    """Per-axis factors of the normal matrix: cofactor diagonal, mirrored sign, max-normalised."""
    sx, sy, sz = scale[:, 0], scale[:, 1], scale[:, 2]
    cof = np.stack([sy * sz, sx * sz, sx * sy], axis=1)
    sign = np.where(sx * sy * sz < 0, -1.0, 1.0)
    peak = np.abs(cof).max(axis=1)
    factor = np.divide(sign, peak, out=np.zeros_like(peak), where=peak > 0)
    return cof * factor[:, None]


def compose_numpy(position: np.ndarray, rotation: np.ndarray, scale: np.ndarray, origin: np.ndarray,
                  model_out: np.ndarray, normal_out: np.ndarray | None = None) -> None:
    """Reference version of `compose` in plain NumPy."""
    rot = quat_to_mat3(rotation)
    model_out[:, :3, :3] = rot * scale[:, None, :]
    model_out[:, :3, 3] = position - origin
    model_out[:, 3, :3] = 0.0
    model_out[:, 3, 3] = 1.0
    if normal_out is not None:
        normal_out[...] = rot * normal_scale(scale)[:, None, :]


def _compose_kernel(position, rotation, scale, origin, model_out, normal_out, with_normal):  # pragma: no cover
    ox, oy, oz = origin[0], origin[1], origin[2]
    for i in range(position.shape[0]):
        x, y, z, w = rotation[i, 0], rotation[i, 1], rotation[i, 2], rotation[i, 3]
        n2 = x * x + y * y + z * z + w * w
        s = 2.0 / n2 if n2 > 0.0 else 0.0
        r00 = 1.0 - s * (y * y + z * z)
        r01 = s * (x * y - z * w)
        r02 = s * (x * z + y * w)
        r10 = s * (x * y + z * w)
        r11 = 1.0 - s * (x * x + z * z)
        r12 = s * (y * z - x * w)
        r20 = s * (x * z - y * w)
        r21 = s * (y * z + x * w)
        r22 = 1.0 - s * (x * x + y * y)
        sx, sy, sz = scale[i, 0], scale[i, 1], scale[i, 2]
        m = model_out[i]
        m[0, 0] = r00 * sx
        m[0, 1] = r01 * sy
        m[0, 2] = r02 * sz
        m[0, 3] = position[i, 0] - ox
        m[1, 0] = r10 * sx
        m[1, 1] = r11 * sy
        m[1, 2] = r12 * sz
        m[1, 3] = position[i, 1] - oy
        m[2, 0] = r20 * sx
        m[2, 1] = r21 * sy
        m[2, 2] = r22 * sz
        m[2, 3] = position[i, 2] - oz
        m[3, 0] = 0.0
        m[3, 1] = 0.0
        m[3, 2] = 0.0
        m[3, 3] = 1.0
        if not with_normal:
            continue
        c0 = sy * sz
        c1 = sx * sz
        c2 = sx * sy
        peak = max(abs(c0), abs(c1), abs(c2))
        f = 0.0
        if peak > 0.0:
            f = 1.0 / peak
            if sx * sy * sz < 0.0:
                f = -f
        c0 *= f
        c1 *= f
        c2 *= f
        nm = normal_out[i]
        nm[0, 0] = r00 * c0
        nm[0, 1] = r01 * c1
        nm[0, 2] = r02 * c2
        nm[1, 0] = r10 * c0
        nm[1, 1] = r11 * c1
        nm[1, 2] = r12 * c2
        nm[2, 0] = r20 * c0
        nm[2, 1] = r21 * c1
        nm[2, 2] = r22 * c2


_compose_native = native.njit(_compose_kernel)


def compose(position: np.ndarray, rotation: np.ndarray, scale: np.ndarray, origin: np.ndarray,
            model_out: np.ndarray, normal_out: np.ndarray | None = None) -> None:
    """Write camera-relative model matrices, and normal matrices when `normal_out` is given,
    for every row.

    position, rotation, scale: (n, 3), (n, 4), (n, 3) float64; origin: (3,) float64;
    model_out: (n, 4, 4) float32; normal_out: (n, 3, 3) float32. Releases the GIL with numba.
    """
    origin = np.asarray(origin, dtype=np.float64)
    if _compose_native is not None:
        with_normal = normal_out is not None
        _compose_native(position, rotation, scale, origin, model_out, normal_out if with_normal else _NO_NORMALS,
                        with_normal)
    else:
        compose_numpy(position, rotation, scale, origin, model_out, normal_out)


_NO_NORMALS = np.empty((0, 3, 3), dtype=np.float32)


# --------------------------------------------------------------------------- motion
def integrate_linear_numpy(position: np.ndarray, linear: np.ndarray, dt: float) -> None:
    position += linear * dt


def integrate_angular_numpy(rotation: np.ndarray, angular: np.ndarray, dt: float) -> None:
    """Reference version of `integrate_angular` in plain NumPy."""
    rate = np.linalg.norm(angular, axis=1)
    half = 0.5 * rate * dt
    safe = np.where(rate > 1e-12, rate, 1.0)
    k = np.where(rate > 1e-12, np.sin(half) / safe, 0.5 * dt)  # sin(half)/rate -> dt/2 as rate -> 0
    dx, dy, dz = (angular[:, i] * k for i in range(3))
    dw = np.cos(half)
    x, y, z, w = (rotation[:, i].copy() for i in range(4))
    nx = dw * x + dx * w + dy * z - dz * y
    ny = dw * y - dx * z + dy * w + dz * x
    nz = dw * z + dx * y - dy * x + dz * w
    nw = dw * w - dx * x - dy * y - dz * z
    norm = np.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
    norm[norm == 0] = 1.0
    rotation[:, 0] = nx / norm
    rotation[:, 1] = ny / norm
    rotation[:, 2] = nz / norm
    rotation[:, 3] = nw / norm


def _linear_kernel(position, linear, dt):  # pragma: no cover
    for i in range(position.shape[0]):
        position[i, 0] += linear[i, 0] * dt
        position[i, 1] += linear[i, 1] * dt
        position[i, 2] += linear[i, 2] * dt


def _angular_kernel(rotation, angular, dt):  # pragma: no cover
    for i in range(rotation.shape[0]):
        ax, ay, az = angular[i, 0], angular[i, 1], angular[i, 2]
        r2 = ax * ax + ay * ay + az * az
        h2 = 0.25 * r2 * dt * dt  # (half angle)^2
        if h2 < 0.01:
            # |half angle| < 0.1: Taylor series of cos(h) and sin(h)/h, both exact to rounding
            # (next terms below 3e-17), and ~4x cheaper than libm's sin and cos.
            dw = 1.0 - h2 * (0.5 - h2 * (1.0 / 24.0 - h2 * (1.0 / 720.0 - h2 / 40320.0)))
            k = 0.5 * dt * (1.0 - h2 * (1.0 / 6.0 - h2 * (1.0 / 120.0 - h2 * (1.0 / 5040.0 - h2 / 362880.0))))
        else:
            rate = np.sqrt(r2)
            half = 0.5 * rate * dt
            dw = np.cos(half)
            k = np.sin(half) / rate
        dx, dy, dz = ax * k, ay * k, az * k
        x, y, z, w = rotation[i, 0], rotation[i, 1], rotation[i, 2], rotation[i, 3]
        nx = dw * x + dx * w + dy * z - dz * y
        ny = dw * y - dx * z + dy * w + dz * x
        nz = dw * z + dx * y - dy * x + dz * w
        nw = dw * w - dx * x - dy * y - dz * z
        norm = np.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
        inv = 1.0 / norm if norm > 0.0 else 1.0
        rotation[i, 0] = nx * inv
        rotation[i, 1] = ny * inv
        rotation[i, 2] = nz * inv
        rotation[i, 3] = nw * inv


_linear_native = native.njit(_linear_kernel)
_angular_native = native.njit(_angular_kernel)


def integrate_linear(position: np.ndarray, linear: np.ndarray, dt: float) -> None:
    """position += linear * dt, in place (GIL released with numba)."""
    if _linear_native is not None:
        _linear_native(position, linear, float(dt))
    else:
        integrate_linear_numpy(position, linear, float(dt))


def integrate_angular(rotation: np.ndarray, angular: np.ndarray, dt: float) -> None:
    """rotation <- exp(angular*dt/2) * rotation, re-normalised, in place. `angular` is a
    world-frame rate (axis * rad/s); the step is exact for a rate constant over dt."""
    if _angular_native is not None:
        _angular_native(rotation, angular, float(dt))
    else:
        integrate_angular_numpy(rotation, angular, float(dt))
