"""The frame's shadow views (issue 15): for every light with a `Shadow` (components/shadow.py),
the views its shadow maps are drawn from (made from the frame's snapshot of the casting lights,
extract/shadows.py), each with its layer of the shadow map array, the
matrices that take render-relative positions there and the planes its casters are culled by.

- directional light: one view per cascade (maths/shadow_cascades.py), fitted to a slice of the
  camera's view from its near plane to `Shadow.distance`, stable under camera motion; casters
  up to `distance` beyond a cascade's sphere towards the light still cast into it;
- spot light: one perspective view from the light along its axis, as wide as its outer cone,
  as deep as its range;
- point light: six views, the faces of a cube in Vulkan's order (+X, -X, +Y, -Y, +Z, -Z) (the
  spec's cube map face selection: a direction's major axis picks the face), each widened by
  CUBE_MARGIN texels: the lighting picks the face itself and filters within one layer, so a
  face's edge needs texels beyond it (no seams). A face is drawn as a camera at the light would
  see it, s = -sc, t = tc: the spec's (sc, tc) are a mirror image (sc x tc = -forward), under
  which the rasteriser's front faces are the back faces seen from the light, and a shadow map
  would hold the casters' far sides where spot and sun maps hold their near ones.

Views come in a fixed order (directional, spot, point lights, each in world order), the layers
numbered in that order. Depth is reverse-Z as everywhere (near 1, far 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...maths.camera import perspective
from ...maths.culling import frustum_planes, frustum_planes_many
from ...maths.shadow_cascades import cascade_splits, fit_cascades, light_rotation, view_slice_sphere
from ..extract.shadows import ShadowCasters
from ..frame.camera import CameraMatrices
from ..lighting.rows import local_minus_z

CUBE_MARGIN = 4  # texels a cube face's map reaches past its edges (PCF's 3x3 bilinear taps need 3)
SPOT_NEAR = 0.01  # a spot or point light's near plane, times its range (0.05 for unbounded ones)
MAX_SPOT_FOV = math.pi - 1e-3  # a 90-degree outer angle still makes a finite projection
# (forward, s axis, t axis) per cube face: the Vulkan spec's table of sc, tc per major axis
CUBE_FACES = (
    ((1, 0, 0), (0, 0, -1), (0, -1, 0)),
    ((-1, 0, 0), (0, 0, 1), (0, -1, 0)),
    ((0, 1, 0), (1, 0, 0), (0, 0, 1)),
    ((0, -1, 0), (1, 0, 0), (0, 0, -1)),
    ((0, 0, 1), (1, 0, 0), (0, -1, 0)),
    ((0, 0, -1), (-1, 0, 0), (0, -1, 0)),
)


@dataclass(frozen=True)
class ShadowView:
    entity: int  # the light's
    kind: str  # "cascade", "spot" or "cube"
    index: int  # the cascade, or the cube face; 0 for a spot light
    layer: int  # in the shadow map array
    view: np.ndarray  # (4, 4) float32: render-relative positions -> the view's frame
    projection: np.ndarray  # (4, 4) float32, reverse-Z
    planes: np.ndarray  # (k, 4) float64: where casters must be (maths/culling.py)
    resolution: int
    texel: float  # world units per texel: a cascade's everywhere; a spot or cube face's at distance 1
    far: float  # a cascade: the far end of its slice of the camera's view; else the light's range (inf: none)
    bias: float = 1.0  # the light's Shadow settings (components/shadow.py)
    normal_offset: float = 1.0
    filter: int = 1
    softness: float = 1.5

    @property
    def view_projection(self) -> np.ndarray:
        return self.projection @ self.view


def _translation_view(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    view = np.eye(4)
    view[:3, :3] = rotation
    view[:3, 3] = -rotation @ position
    return view


def cube_face_scale(resolution: int) -> float:
    """How much a cube face's s and t are shrunk so that CUBE_MARGIN texels beyond its edges
    still land on the map: the lighting filters near a face's edge without reading past it."""
    return resolution / (resolution + 2.0 * CUBE_MARGIN)


def _cube_face(face: int, near: float, far: float, scale: float = 1.0) -> np.ndarray:
    """(4, 4) float64: a direction r from the light -> clip (-sc, tc, depth, ma) * (scale, scale,
    1, 1), ma = r on the face's major axis; x/w and y/w are then in [-1, 1] (t down the image,
    as Vulkan's NDC y), shrunk by `scale`, depth reverse-Z from `near` (1) to `far` (0, or
    infinite). The spec's sc is negated (the module says why): x x y = forward, as in every
    other view (maths/camera.py's projections), so the shadow pipelines' winding holds."""
    forward, s_axis, t_axis = (np.array(v, np.float64) for v in CUBE_FACES[face])
    m = np.zeros((4, 4))
    m[0, :3], m[1, :3], m[3, :3] = -s_axis * scale, t_axis * scale, forward
    if math.isinf(far):
        m[2, 3] = near
    else:
        m[2, :3] = -near / (far - near) * forward
        m[2, 3] = far * near / (far - near)
    return m


def shadow_views(
    casters: ShadowCasters | None, cam: CameraMatrices, origin: np.ndarray, only: set[int] | None = None
) -> list[ShadowView]:
    """The views of every shadow-casting light (or of the lights whose entities are in `only`),
    in layer order (see the module)."""
    origin = np.asarray(origin, np.float64)
    eye = cam.position - origin
    forward = cam.inverse_view[:3, :3].astype(np.float64) @ np.array([0.0, 0.0, -1.0])
    views: list[ShadowView] = []
    if casters is None:
        return views

    def add(
        entity: int,
        kind: str,
        index: int,
        view: np.ndarray,
        projection: np.ndarray,
        resolution: int,
        texel: float,
        far: float,
        shadow: Any,
        row: int,
        planes: np.ndarray | None = None,
    ) -> None:
        view32, projection32 = view.astype(np.float32, copy=False), projection.astype(np.float32, copy=False)
        if planes is None:
            planes = frustum_planes(projection32, view32)
        settings = (
            float(shadow.bias[row]),
            float(shadow.normal_offset[row]),
            int(shadow.filter[row]),
            float(shadow.softness[row]),
        )
        views.append(
            ShadowView(entity, kind, index, len(views), view32, projection32, planes, resolution, texel, far, *settings)
        )

    for rows in casters.directional:
        shadow = rows.shadow
        directions = local_minus_z(rows.rotation)
        for row, entity in enumerate(rows.entities.tolist()):
            if only is not None and entity not in only:
                continue
            distance = float(shadow.distance[row])
            far = min(distance, cam.far)
            if far <= cam.near:
                continue  # the camera sees nothing within the shadow distance
            splits = cascade_splits(cam.near, far, int(shadow.cascades[row])).tolist()
            resolution = int(shadow.resolution[row])
            spheres = [view_slice_sphere(cam.lens, splits[i], splits[i + 1]) for i in range(len(splits) - 1)]
            centres = eye + np.array([along for along, _ in spheres])[:, None] * forward
            cascades = fit_cascades(
                centres, [radius for _, radius in spheres], origin, directions[row], resolution, distance,
                splits[:-1], splits[1:],
            )  # fmt: skip
            clip = np.array([c.projection for c in cascades], np.float64) @ np.array([c.view for c in cascades])
            planes = frustum_planes_many(clip)
            for i, c in enumerate(cascades):
                far_i = splits[i + 1]
                add(entity, "cascade", i, c.view, c.projection, resolution, c.texel, far_i, shadow, row, planes[i])

    for rows in casters.spot:
        shadow = rows.shadow
        directions = local_minus_z(rows.rotation)
        for row, entity in enumerate(rows.entities.tolist()):
            if only is not None and entity not in only:
                continue
            reach = float(rows.radius[row])
            far = reach if reach > 0 else math.inf
            fov = min(2.0 * float(rows.outer_angle[row]), MAX_SPOT_FOV)
            projection = perspective(fov, 1.0, SPOT_NEAR * reach if reach > 0 else 0.05, far).astype(np.float64)
            view = _translation_view(light_rotation(directions[row]), rows.position[row] - origin)
            resolution = int(shadow.resolution[row])
            add(
                entity,
                "spot",
                0,
                view,
                projection,
                resolution,
                2.0 * math.tan(0.5 * fov) / resolution,
                far,
                shadow,
                row,
            )

    for rows in casters.point:
        shadow = rows.shadow
        for row, entity in enumerate(rows.entities.tolist()):
            if only is not None and entity not in only:
                continue
            reach = float(rows.radius[row])
            far = reach if reach > 0 else math.inf
            near = SPOT_NEAR * reach if reach > 0 else 0.05
            view = _translation_view(np.eye(3), rows.position[row] - origin)
            resolution = int(shadow.resolution[row])
            for face in range(6):
                add(
                    entity,
                    "cube",
                    face,
                    view,
                    _cube_face(face, near, far, cube_face_scale(resolution)),
                    resolution,
                    2.0 / (resolution * cube_face_scale(resolution)),
                    far,
                    shadow,
                    row,
                )
    return views


PROJECTIONS = {"cascade": 0, "spot": 1, "cube": 2}  # SHADOW_VIEW.info.w: orthographic, perspective, a cube face


def light_views(views: list[ShadowView]) -> dict[int, tuple[int, int]]:
    """Per shadow-casting light's entity: its first view and count, which its light row
    names (light_rows.write_light_shadows)."""
    first: dict[int, tuple[int, int]] = {}
    for v in views:
        start, count = first.get(v.entity, (v.layer, 0))
        first[v.entity] = (start, count + 1)
    return first


def write_view_rows(out: np.ndarray, views: list[ShadowView], resolution: int) -> None:
    """SHADOW_VIEW rows of the views (shading.glsl's light_shadow reads them). Every layer
    has the maps' resolution, the largest any light asks for; a view is drawn in the corner
    of its layer at its own light's resolution (ShadowPass.target_state), which the lighting's map
    coordinates are scaled by (depth_model.w), and its bias, PCF width and PCSS search are in
    its own texels."""
    size = float(resolution)
    for k, v in enumerate(views):
        perspective = v.kind != "cascade"
        p = v.projection.astype(np.float64)
        row = out[k]
        row["view_projection"] = (p @ v.view.astype(np.float64)).T
        if perspective:  # depth = P22 + P23 / d: a world bias b at distance d is P23 * b / d^2
            bias, offset = p[2, 3] * v.bias * v.texel, v.normal_offset * v.texel
        else:  # depth = P22 * z + P23: linear
            bias, offset = p[2, 2] * v.bias * v.texel, v.normal_offset * v.texel
        row["params"] = (bias, offset, v.far if np.isfinite(v.far) else 3.0e38, v.softness)
        row["info"] = (v.layer, v.filter, v.resolution, PROJECTIONS[v.kind])
        row["depth_model"] = (p[2, 2], p[2, 3], v.texel, min(v.resolution, size) / size)
