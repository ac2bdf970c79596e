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

from .. import native


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


def compose_numpy(
    position: np.ndarray,
    rotation: np.ndarray,
    scale: np.ndarray,
    origin: np.ndarray,
    model_out: np.ndarray,
    normal_out: np.ndarray | None = None,
) -> None:
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


def compose(
    position: np.ndarray,
    rotation: np.ndarray,
    scale: np.ndarray,
    origin: np.ndarray,
    model_out: np.ndarray,
    normal_out: np.ndarray | None = None,
) -> None:
    """Write camera-relative model matrices, and normal matrices when `normal_out` is given,
    for every row.

    position, rotation, scale: (n, 3), (n, 4), (n, 3) float64; origin: (3,) float64;
    model_out: (n, 4, 4) float32; normal_out: (n, 3, 3) float32. Releases the GIL with numba.
    """
    origin = np.asarray(origin, dtype=np.float64)
    if _compose_native is not None:
        with_normal = normal_out is not None
        _compose_native(
            position, rotation, scale, origin, model_out, normal_out if with_normal else _NO_NORMALS, with_normal
        )
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


# The motion kernels index flat views of their C-contiguous (n, 3) and (n, 4) arrays: numba
# indexes 2-D arrays in a way LLVM does not vectorise, flat ones it does (angular motion:
# 11.7 -> 5.2 ms per 1M rows on the dev box).
def _linear_kernel(position, linear, dt):  # pragma: no cover
    p = position.reshape(position.size)
    v = linear.reshape(linear.size)
    for j in range(p.shape[0]):
        p[j] += v[j] * dt


_SMALL_H2 = 0.01  # (half angle)^2 below which the Taylor series are exact to rounding


def _angular_small_kernel(rotation_2d, angular_2d, dt):  # pragma: no cover
    # Every row whose |half angle| < 0.1 (almost all at frame rates): the Taylor series of
    # cos(h) and sin(h)/h, exact to rounding (next terms below 3e-17) and ~4x cheaper than libm.
    # Other rows (and NaN rates) are left as they are and counted for _angular_large_kernel:
    # with the sin/cos branch inside, this loop would not vectorise.
    rotation = rotation_2d.reshape(rotation_2d.size)
    angular = angular_2d.reshape(angular_2d.size)
    large = 0
    for i in range(rotation.shape[0] // 4):
        ax, ay, az = angular[3 * i], angular[3 * i + 1], angular[3 * i + 2]
        h2 = 0.25 * (ax * ax + ay * ay + az * az) * dt * dt  # (half angle)^2
        small = h2 < _SMALL_H2
        dw = 1.0 - h2 * (0.5 - h2 * (1.0 / 24.0 - h2 * (1.0 / 720.0 - h2 / 40320.0)))
        k = 0.5 * dt * (1.0 - h2 * (1.0 / 6.0 - h2 * (1.0 / 120.0 - h2 * (1.0 / 5040.0 - h2 / 362880.0))))
        if not small:
            dw, k = 1.0, 0.0  # the identity: the row comes out unchanged
        large += 0 if small else 1
        o = 4 * i
        inv = _turn(rotation, o, ax * k, ay * k, az * k, dw)
        if not small:
            inv = 1.0
        rotation[o] *= inv
        rotation[o + 1] *= inv
        rotation[o + 2] *= inv
        rotation[o + 3] *= inv
    return large


def _angular_large_kernel(rotation_2d, angular_2d, dt):  # pragma: no cover
    # The rows _angular_small_kernel left: libm's sin and cos.
    rotation = rotation_2d.reshape(rotation_2d.size)
    angular = angular_2d.reshape(angular_2d.size)
    for i in range(rotation.shape[0] // 4):
        ax, ay, az = angular[3 * i], angular[3 * i + 1], angular[3 * i + 2]
        r2 = ax * ax + ay * ay + az * az
        if 0.25 * r2 * dt * dt < _SMALL_H2:
            continue
        rate = np.sqrt(r2)
        half = 0.5 * rate * dt
        k = np.sin(half) / rate
        o = 4 * i
        inv = _turn(rotation, o, ax * k, ay * k, az * k, np.cos(half))
        rotation[o] *= inv
        rotation[o + 1] *= inv
        rotation[o + 2] *= inv
        rotation[o + 3] *= inv


def _turn_kernel(rotation, o, dx, dy, dz, dw):  # pragma: no cover
    # rotation[o:o+4] <- (dx, dy, dz, dw) * rotation[o:o+4]; returns 1/|result| (1 for zero).
    x, y, z, w = rotation[o], rotation[o + 1], rotation[o + 2], rotation[o + 3]
    nx = dw * x + dx * w + dy * z - dz * y
    ny = dw * y - dx * z + dy * w + dz * x
    nz = dw * z + dx * y - dy * x + dz * w
    nw = dw * w - dx * x - dy * y - dz * z
    rotation[o], rotation[o + 1], rotation[o + 2], rotation[o + 3] = nx, ny, nz, nw
    n2 = nx * nx + ny * ny + nz * nz + nw * nw
    return 1.0 / np.sqrt(n2) if n2 > 0.0 else 1.0


_turn = native.inner(_turn_kernel)
_linear_native = native.njit(_linear_kernel)
_angular_small = native.njit(_angular_small_kernel)
_angular_large = native.njit(_angular_large_kernel)


def integrate_linear(position: np.ndarray, linear: np.ndarray, dt: float) -> None:
    """position += linear * dt, in place (GIL released with numba)."""
    if (
        _linear_native is not None
        and linear.shape == position.shape
        and position.flags.c_contiguous
        and linear.flags.c_contiguous
    ):
        _linear_native(position, linear, float(dt))
    else:
        integrate_linear_numpy(position, linear, float(dt))


def integrate_angular(rotation: np.ndarray, angular: np.ndarray, dt: float) -> None:
    """rotation <- exp(angular*dt/2) * rotation, re-normalised, in place. `angular` is a
    world-frame rate (axis * rad/s); the step is exact for a rate constant over dt."""
    if (
        _angular_small is None
        or _angular_large is None
        or angular.shape != (len(rotation), 3)
        or not rotation.flags.c_contiguous
        or not angular.flags.c_contiguous
    ):
        integrate_angular_numpy(rotation, angular, float(dt))  # strided views: still in place
    elif _angular_small(rotation, angular, float(dt)):
        _angular_large(rotation, angular, float(dt))
