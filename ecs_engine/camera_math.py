"""Camera matrices: reverse-Z projections in Vulkan clip space, rotation-only views.

Conventions (see ecs_engine.transform_math): right-handed, Y up, the camera looks down -Z in its
own frame; matrices are indexed [row, column] and multiply column vectors; quaternions are
(x, y, z, w). Clip space is Vulkan's: NDC y points down (so the projection flips Y to keep world
+Y up on screen) and depth lies in [0, 1]. Depth is reversed (near -> 1, far or infinity -> 0,
cleared to 0, compare GREATER): float32's dense exponents near 0 then meet the 1/distance
crowding of perspective depth, so depth keeps ~7 significant digits at any distance.

Rendering is camera-relative: model matrices already have the camera position subtracted (in
float64, see systems/transform.py), so the view matrix is a pure rotation with no translation.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ecs_engine.components.camera import ORTHOGRAPHIC, Camera
from ecs_engine.components.camera_control import ActiveCamera
from ecs_engine.components.transform import Transform

from .errors import UsageError

if TYPE_CHECKING:
    from .ecs.world import World


def _check_positive(name: str, value: float) -> None:
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
    _check_positive("aspect", aspect)
    _check_positive("near", near)
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
    _check_positive("height", height)
    _check_positive("aspect", aspect)
    if not (math.isfinite(near) and math.isfinite(far)) or far <= near:
        raise ValueError(
            f"an orthographic projection needs finite near < far, got near={near!r}, far={far!r}"
        )
    m = np.zeros((4, 4), dtype=np.float64)
    m[0, 0] = 2.0 / (height * aspect)
    m[1, 1] = -2.0 / height  # Vulkan y flip
    m[2, 2] = 1.0 / (far - near)
    m[2, 3] = far / (far - near)  # depth = (far - d) / (far - near) with d = -z
    m[3, 3] = 1.0
    return m.astype(np.float32)


def rotation_matrix(rotation_quat: np.ndarray) -> np.ndarray:
    """(4, 4) float64 rotation of a quaternion (x, y, z, w); non-unit input is normalised.

    Scalar Python arithmetic: for one quaternion a frame, NumPy's per-call overhead made this
    ~40 us; the same formula as transform_math.quat_to_mat3."""
    q = np.asarray(rotation_quat, dtype=np.float64).reshape(4)
    x, y, z, w = q.tolist()
    n2 = x * x + y * y + z * z + w * w
    if not math.isfinite(n2) or n2 == 0.0:
        raise ValueError(f"rotation must be a finite non-zero quaternion, got {q.tolist()}")
    s = 2.0 / n2
    return np.array([
        [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w), 0.0],
        [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w), 0.0],
        [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y), 0.0],
        [0.0, 0.0, 0.0, 1.0]])


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


@dataclass(frozen=True)
class CameraMatrices:
    """What a frame needs from the active camera. `view` maps camera-relative world directions
    to view space (rotation only); `inverse_view` maps back; `position` (float64) is the render
    origin to subtract from world positions before the cast to float32."""

    projection: np.ndarray
    view: np.ndarray
    inverse_view: np.ndarray
    position: np.ndarray
    near: float
    far: float
    entity: int


def view_from_origin(cam: CameraMatrices, origin: np.ndarray) -> np.ndarray:
    """The view matrix (4, 4) float32 for model matrices made relative to `origin`: the camera's
    rotation, and the translation from origin to camera (made in float64, cast once). With the
    origin at the camera (camera-relative rendering) the translation is exactly zero."""
    view = cam.view.astype(np.float64)
    view[:3, 3] = view[:3, :3] @ (np.asarray(origin, dtype=np.float64) - cam.position)
    return view.astype(np.float32)


def active_camera(world: World) -> int:
    """The entity to render from: the only one with Camera and Transform, or else the only one
    of those also tagged ActiveCamera. Raises UsageError otherwise."""
    cached = _ACTIVE.get(world)
    if cached is not None and cached[0] == world.structure_version:
        return cached[1]  # which entity it is can only change with the world's structure
    cameras = world.query(Camera, Transform, write=()).entities()
    if len(cameras) == 1:
        _ACTIVE[world] = (world.structure_version, int(cameras[0]))
        return int(cameras[0])
    if len(cameras) == 0:
        raise UsageError("no camera: spawn an entity with Camera and Transform components")
    tagged = world.query(Camera, Transform, with_=[ActiveCamera], write=()).entities()
    if len(tagged) == 1:
        _ACTIVE[world] = (world.structure_version, int(tagged[0]))
        return int(tagged[0])
    if len(tagged) == 0:
        raise UsageError(
            f"{len(cameras)} entities have Camera and Transform and none is tagged ActiveCamera: "
            "add ActiveCamera() to the one to render from"
        )
    raise UsageError(
        f"{len(tagged)} cameras are tagged ActiveCamera: remove the tag from all but one"
    )


def camera_matrices(world: World, viewport_aspect: float) -> CameraMatrices:
    """Projection, view and position of the active camera (see `active_camera`).
    Camera.aspect 0 means "use viewport_aspect" (width / height of the render target).

    The result is kept until the camera's Camera or Transform columns are written (see
    World.change_stamp), so a still camera costs a lookup; its arrays are read-only."""
    viewport_aspect = float(viewport_aspect)
    _check_positive("viewport_aspect", viewport_aspect)
    eid = active_camera(world)
    stamp = (world.change_stamp(eid, Camera, Transform), viewport_aspect)
    cached = _MATRICES.get(world)
    if cached is not None and cached[0] == stamp:
        return cached[1]
    matrices = _camera_matrices(world, eid, viewport_aspect)
    for array in (matrices.projection, matrices.view, matrices.inverse_view, matrices.position):
        array.flags.writeable = False
    _MATRICES[world] = (stamp, matrices)
    return matrices


# per world: (structure_version, active camera) and (change stamp, CameraMatrices)
_ACTIVE: weakref.WeakKeyDictionary[Any, tuple[int, int]] = weakref.WeakKeyDictionary()
_MATRICES: weakref.WeakKeyDictionary[Any, tuple[Any, CameraMatrices]] = weakref.WeakKeyDictionary()


def _camera_matrices(world: World, eid: int, viewport_aspect: float) -> CameraMatrices:
    cam = world.get(eid, Camera)
    transform = world.get(eid, Transform)
    aspect = float(cam.aspect) or viewport_aspect
    near, far = float(cam.near), float(cam.far)
    if int(cam.projection) == ORTHOGRAPHIC:
        if math.isinf(far):
            raise UsageError(
                f"the orthographic camera (entity {eid}) has an infinite far plane: "
                "set Camera.far to a finite distance"
            )
        projection = orthographic(float(cam.height), aspect, near, far)
    else:
        projection = perspective(float(cam.fov_y), aspect, near, far)
    rotation = rotation_matrix(transform.rotation)
    return CameraMatrices(
        projection=projection,
        view=rotation.T.astype(np.float32),
        inverse_view=rotation.astype(np.float32),
        position=np.array(transform.position, dtype=np.float64),
        near=near,
        far=far,
        entity=eid,
    )
