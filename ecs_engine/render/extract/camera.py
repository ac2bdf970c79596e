"""Extract: the active camera's matrices for a frame, what its Camera and Transform components
make of the projections in maths/camera.py, kept while neither component changes. Reads the
Camera and Transform columns (and the active-camera tag) only."""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecs_engine.components.camera import ORTHOGRAPHIC, ActiveCamera, Camera, active_camera
from ecs_engine.components.transform import Transform

from ...ecs.world import World
from ...errors import UsageError
from ...maths.camera import check_positive, check_region, orthographic, perspective, region_projection, rotation_matrix

READS = (Camera, Transform, ActiveCamera)  # a system running camera_matrices declares these


@dataclass(frozen=True)
class CameraMatrices:
    """What a frame needs from the active camera. `view` maps camera-relative world directions
    to view space (rotation only); `inverse_view` maps back; `position` (float64) is the render
    origin to subtract from world positions before the cast to float32."""

    projection: np.ndarray  # what the frame is drawn with (off-axis when drawn into a region)
    view: np.ndarray
    inverse_view: np.ndarray
    position: np.ndarray
    near: float
    far: float
    entity: int
    lens: np.ndarray  # the symmetric projection of the region itself (= projection without one)


def camera_matrices(
    world: World, viewport_aspect: float, region: tuple[float, float, float, float] | None = None
) -> CameraMatrices:
    """Projection, view and position of the active camera (see `active_camera`).
    Camera.aspect 0 means "use viewport_aspect" (width / height of the render target).
    `region` (x0, y0, x1, y1, fractions from the top left): the part of the target the view is
    for (the editor's central node); the projection then draws the whole target so that the
    region shows the camera's view (maths/camera.py's region_projection), `lens` is the region's.

    The result is kept until the camera's Camera or Transform columns are written (see
    World.change_stamp), so a still camera costs a lookup; its arrays are read-only."""
    return camera_matrices_of(world, active_camera(world), viewport_aspect, region)


def camera_matrices_of(
    world: World, eid: int, viewport_aspect: float, region: tuple[float, float, float, float] | None = None
) -> CameraMatrices:
    """camera_matrices for the camera `eid` (one of several drawing: extract/views.py)."""
    viewport_aspect = float(viewport_aspect)
    check_positive("viewport_aspect", viewport_aspect)
    region = None if region is None else check_region(region)
    stamp = (world.change_stamp(eid, Camera, Transform), viewport_aspect, region)
    kept = _MATRICES.get(world)
    if kept is None:
        kept = _MATRICES[world] = {}
    cached = kept.get(eid)
    if cached is not None and cached[0] == stamp:
        return cached[1]
    matrices = _camera_matrices(world, eid, viewport_aspect, region)
    for array in (matrices.projection, matrices.view, matrices.inverse_view, matrices.position, matrices.lens):
        array.flags.writeable = False
    if len(kept) > MAX_KEPT:  # cameras come and go: keep the ones drawing now
        kept.clear()
    kept[eid] = (stamp, matrices)
    return matrices


extract_camera = camera_matrices  # the extract stage's name for it (extract/__init__.py)

MAX_KEPT = 64  # cameras whose matrices are kept per world
# per world: camera entity -> (change stamp, CameraMatrices)
_MATRICES: weakref.WeakKeyDictionary[Any, dict[int, tuple[Any, CameraMatrices]]] = weakref.WeakKeyDictionary()


def _camera_matrices(
    world: World, eid: int, viewport_aspect: float, region: tuple[float, float, float, float] | None
) -> CameraMatrices:
    cam = world.get(eid, Camera)
    transform = world.get(eid, Transform)
    if region is not None:
        viewport_aspect *= (region[2] - region[0]) / (region[3] - region[1])
    aspect = float(cam.aspect) or viewport_aspect
    near, far = float(cam.near), float(cam.far)
    if int(cam.projection) == ORTHOGRAPHIC:
        if math.isinf(far):
            raise UsageError(
                f"the orthographic camera (entity {eid}) has an infinite far plane: set Camera.far to a finite distance"
            )
        projection = orthographic(float(cam.height), aspect, near, far)
    else:
        projection = perspective(float(cam.fov_y), aspect, near, far)
    rotation = rotation_matrix(transform.rotation)
    return CameraMatrices(
        projection=projection if region is None else region_projection(projection, region),
        view=rotation.T.astype(np.float32),
        inverse_view=rotation.astype(np.float32),
        position=np.array(transform.position, dtype=np.float64),
        near=near,
        far=far,
        entity=eid,
        lens=projection,
    )
