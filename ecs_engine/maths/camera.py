"""Camera matrices: reverse-Z projections in Vulkan clip space, rotation-only views.

Conventions (see ecs_engine.maths.transform): right-handed, Y up, the camera looks down -Z in its
own frame; matrices are indexed [row, column] and multiply column vectors; quaternions are
(x, y, z, w). Clip space is Vulkan's: NDC y points down (so the projection flips Y to keep world
+Y up on screen) and depth lies in [0, 1]. Depth is reversed (near -> 1, far or infinity -> 0,
cleared to 0, compare GREATER): float32's dense exponents near 0 then meet the 1/distance
crowding of perspective depth, so depth keeps ~7 significant digits at any distance.

Rendering is camera-relative: model matrices already have the camera position subtracted (in
float64, see systems/transform.py), so the view matrix is a pure rotation with no translation.
What the active camera's components make of these is in render/frame/camera.py.
"""

from __future__ import annotations

import math

import numpy as np


def check_positive(name: str, value: float) -> None:
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")


def perspective(fov_y: float, aspect: float, near: float, far: float = math.inf) -> np.ndarray:
    """Reverse-Z perspective projection, (4, 4) float32.

    fov_y: full vertical field of view in radians, in (0, pi); aspect: width / height;
    far may be +inf. A point at view depth d (z = -d) gets depth near/d (infinite far) or
    near*(far - d) / ((far - near)*d) (finite far), so near -> 1 and far -> 0.
    """
    fov_y, aspect, near, far = float(fov_y), float(aspect), float(near), float(far)
    if not (0.0 < fov_y < math.pi):
        raise ValueError(f"fov_y must be in (0, pi) radians, got {fov_y!r}")
    check_positive("aspect", aspect)
    check_positive("near", near)
    if math.isnan(far) or far <= near:
        raise ValueError(f"far ({far!r}) must be greater than near ({near!r}) or +inf")
    f = 1.0 / math.tan(0.5 * fov_y)
    m = np.zeros((4, 4), dtype=np.float64)
    m[0, 0] = f / aspect
    m[1, 1] = -f  # Vulkan NDC y points down: flip so world +Y is up on screen
    if math.isinf(far):
        m[2, 3] = near  # z_clip = near, w_clip = d  ->  depth = near / d
    else:
        m[2, 2] = near / (far - near)
        m[2, 3] = far * near / (far - near)
    m[3, 2] = -1.0  # w_clip = -z_view = distance in front of the camera
    return m.astype(np.float32)


def orthographic(height: float, aspect: float, near: float, far: float) -> np.ndarray:
    """Reverse-Z orthographic projection, (4, 4) float32; `height` is the view's full height.

    Depth is linear: near -> 1, far -> 0. The far plane must be finite (a linear depth over an
    infinite range has no resolution left).
    """
    height, aspect, near, far = float(height), float(aspect), float(near), float(far)
    check_positive("height", height)
    check_positive("aspect", aspect)
    if not (math.isfinite(near) and math.isfinite(far)) or far <= near:
        raise ValueError(f"an orthographic projection needs finite near < far, got near={near!r}, far={far!r}")
    m = np.zeros((4, 4), dtype=np.float64)
    m[0, 0] = 2.0 / (height * aspect)
    m[1, 1] = -2.0 / height  # Vulkan y flip
    m[2, 2] = 1.0 / (far - near)
    m[2, 3] = far / (far - near)  # depth = (far - d) / (far - near) with d = -z
    m[3, 3] = 1.0
    return m.astype(np.float32)


def check_region(region: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1): a part of a render target, fractions of its size from the top left."""
    x0, y0, x1, y1 = (float(v) for v in region)
    if not (0.0 <= x0 < x1 <= 1.0 and 0.0 <= y0 < y1 <= 1.0):
        raise ValueError(f"a region is (x0, y0, x1, y1) with 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1, got {region!r}")
    return x0, y0, x1, y1


def region_projection(lens: np.ndarray, region: tuple[float, float, float, float]) -> np.ndarray:
    """The projection for the whole target that shows, inside `region` (check_region), exactly what
    `lens` (made with the region's aspect) shows over a whole target: an off-axis frustum, so a
    view drawn full-window appears centred and undistorted in the region (the editor's central
    node). Clip x' = sx x + cx w, where sx is the region's width fraction and cx its centre in NDC;
    y likewise (Vulkan's NDC y points down, as fractions from the top do). float32."""
    x0, y0, x1, y1 = check_region(region)
    t = np.eye(4)
    t[0, 0], t[0, 3] = x1 - x0, x0 + x1 - 1.0
    t[1, 1], t[1, 3] = y1 - y0, y0 + y1 - 1.0
    # the w row of an orthographic lens is (0, 0, 0, 1), of a perspective one (0, 0, -1, 0): both
    # carry the shift into x and y as w does
    return (t @ np.asarray(lens, np.float64)).astype(np.float32)


def rotation_matrix(rotation_quat: np.ndarray) -> np.ndarray:
    """(4, 4) float64 rotation of a quaternion (x, y, z, w); non-unit input is normalised.

    Scalar Python arithmetic: for one quaternion a frame, NumPy's per-call overhead made this
    ~40 us; the same formula as maths.transform.quat_to_mat3."""
    q = np.asarray(rotation_quat, dtype=np.float64).reshape(4)
    x, y, z, w = q.tolist()
    n2 = x * x + y * y + z * z + w * w
    if not math.isfinite(n2) or n2 == 0.0:
        raise ValueError(f"rotation must be a finite non-zero quaternion, got {q.tolist()}")
    s = 2.0 / n2
    return np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w), 0.0],
            [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w), 0.0],
            [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y), 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def view_rotation(rotation_quat: np.ndarray) -> np.ndarray:
    """The view matrix of a camera with this world rotation: its inverse (the transpose), (4, 4)
    float32, with no translation because model matrices are already camera-relative."""
    return rotation_matrix(rotation_quat).T.astype(np.float32)


def yaw_pitch_quat(yaw: float | np.ndarray, pitch: float | np.ndarray) -> np.ndarray:
    """Rotation (x, y, z, w) float64: yaw about world +Y, then pitch about the camera's own +X.

    Yaw 0, pitch 0 looks down -Z; positive yaw turns the view toward -X (counter-clockwise seen
    from above), positive pitch looks up. Arrays broadcast to (..., 4). It is q_yaw * q_pitch
    written out, so it is unit length to rounding and never accumulates error.
    """
    half_yaw = 0.5 * np.asarray(yaw, dtype=np.float64)
    half_pitch = 0.5 * np.asarray(pitch, dtype=np.float64)
    sy, cy = np.sin(half_yaw), np.cos(half_yaw)
    sp, cp = np.sin(half_pitch), np.cos(half_pitch)
    return np.stack(np.broadcast_arrays(cy * sp, sy * cp, -sy * sp, cy * cp), axis=-1)


def yaw_pitch_roll_quat(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Rotation (x, y, z, w): yaw about world +Y, then pitch about the local +X, then roll about
    the local +Z (R = Ry Rx Rz); roll 0 gives yaw_pitch_quat. For editing, in radians."""
    sy, cy = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
    sp, cp = math.sin(0.5 * pitch), math.cos(0.5 * pitch)
    sr, cr = math.sin(0.5 * roll), math.cos(0.5 * roll)
    # q_yaw * q_pitch = (cy*sp, sy*cp, -sy*sp, cy*cp), then * q_roll = (0, 0, sr, cr)
    x, y, z, w = cy * sp, sy * cp, -sy * sp, cy * cp
    return np.array([x * cr + y * sr, y * cr - x * sr, z * cr + w * sr, w * cr - z * sr])


def yaw_pitch_roll(rotation_quat: np.ndarray) -> tuple[float, float, float]:
    """The angles of `yaw_pitch_roll_quat` for a rotation (radians; pitch in [-pi/2, pi/2])."""
    r = rotation_matrix(rotation_quat)
    pitch = math.asin(max(-1.0, min(1.0, -r[1, 2])))
    if abs(r[1, 2]) > 1.0 - 1e-9:  # looking straight up or down: yaw and roll share one axis
        return math.atan2(-r[2, 0], r[0, 0]), pitch, 0.0
    return math.atan2(r[0, 2], r[2, 2]), pitch, math.atan2(r[1, 0], r[1, 1])


def look_rotation(direction: np.ndarray | tuple[float, float, float]) -> np.ndarray:
    """The rotation (x, y, z, w) whose local -Z axis points along `direction` and whose +X stays
    level (yaw, then pitch, as yaw_pitch_quat): how cameras, spot and directional lights aim."""
    d = np.asarray(direction, dtype=np.float64)
    if d.shape != (3,) or not np.isfinite(d).all() or not d.any():
        raise ValueError(f"direction must be 3 finite numbers, not all 0, got {direction!r}")
    return yaw_pitch_quat(math.atan2(-d[0], -d[2]), math.atan2(d[1], math.hypot(d[0], d[2])))
