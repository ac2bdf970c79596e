"""Cascaded shadow maps for directional lights: where the view is split and how each cascade's
light projection is fitted to its slice so that it does not shimmer (issue 15).

The view from `near` to the shadow distance is cut into up to four slices (`cascade_splits`:
the practical scheme of Zhang et al., "Parallel-split shadow maps", 2006, a blend of uniform and
logarithmic splits). Each slice is enclosed in a sphere (`slice_sphere`), and the cascade's
orthographic projection is the square around that sphere, seen along the light (`fit_cascade`):

- a sphere's size depends only on the field of view, the aspect and the split distances, never
  on where the camera looks, so turning the camera does not change the cascade's texel size;
- the square's centre is snapped to whole shadow-map texels in the light's frame, measured from
  the world origin (not from the camera-relative render origin, which moves with the camera),
  so translating the camera moves the map's texel grid by whole texels: a static scene's shadow
  edges stay where they are (after M. Valient, "Stable rendering of cascaded shadow maps",
  ShaderX6, 2008).

Conventions are those of maths/camera.py: right-handed, Y up, looking down -Z, matrices
[row, column] on column vectors, reverse-Z depth in [0, 1] (near 1, far 0), Vulkan NDC (y down).
Positions given to `fit_cascade` are relative to the render origin, which is `origin` in the
world; the view matrix it returns takes render-relative positions, like the camera's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .camera import check_positive

MAX_CASCADES = 4  # components/shadow.py: Shadow.cascades


def cascade_splits(near: float, far: float, count: int, blend: float = 0.75) -> np.ndarray:
    """`count` + 1 view distances from `near` to `far`: split i is blend * log_i + (1 - blend) *
    uniform_i (blend 1: logarithmic, the same ratio each cascade; 0: uniform)."""
    check_positive("near", near)
    if not (math.isfinite(far) and far > near):
        raise ValueError(f"the shadow distance ({far!r}) must be finite and beyond near ({near!r})")
    if not 1 <= count <= MAX_CASCADES:
        raise ValueError(f"cascades must be 1 to {MAX_CASCADES}, got {count!r}")
    if not 0.0 <= blend <= 1.0:
        raise ValueError(f"the split blend must be in [0, 1], got {blend!r}")
    i = np.arange(count + 1, dtype=np.float64) / count
    splits = blend * near * (far / near) ** i + (1.0 - blend) * (near + (far - near) * i)
    splits[0], splits[-1] = near, far  # exactly, whatever the rounding
    return splits


def slice_sphere(d0: float, d1: float, tan_half_fov_y: float, aspect: float) -> tuple[float, float]:
    """(distance of the centre along the view axis, radius) of the smallest sphere around the
    perspective frustum slice between view distances d0 < d1. A slice's corners lie at distance
    d along the axis, k * d off it (k: the tangent of the half diagonal field of view); the
    centre is where its distances to a near and a far corner are equal, unless that lies beyond
    d1 (a wide slice), where the far cap's circle alone decides."""
    k2 = tan_half_fov_y * tan_half_fov_y * (1.0 + aspect * aspect)
    centre = 0.5 * (d0 + d1) * (1.0 + k2)
    if centre >= d1:
        return d1, math.sqrt(k2) * d1
    return centre, math.sqrt((centre - d0) ** 2 + k2 * d0 * d0)


def light_rotation(direction: np.ndarray) -> np.ndarray:
    """(3, 3) rows: the light frame's right, up and back axes (back = -direction, the way the
    light comes from), so that R @ p gives a point in the light's frame looking down -Z. Up is
    world +Y projected, or +Z when the light shines (almost) straight up or down."""
    x, y, z = (float(v) for v in np.asarray(direction, np.float64).reshape(3))
    # scalar maths: numpy's cross on 3-vectors costs 20x more, per frame and cascade
    n = math.sqrt(x * x + y * y + z * z)
    if not (math.isfinite(n) and n > 0.0):
        raise ValueError(f"a light direction must be finite and non-zero, got {[x, y, z]}")
    bx, by, bz = -x / n, -y / n, -z / n
    if abs(by) < 0.999:  # right = up_hint x back, up_hint +Y
        rx, ry, rz = bz, 0.0, -bx
    else:  # up_hint +Z
        rx, ry, rz = -by, bx, 0.0
    r = math.sqrt(rx * rx + ry * ry + rz * rz)
    rx, ry, rz = rx / r, ry / r, rz / r
    ux, uy, uz = by * rz - bz * ry, bz * rx - bx * rz, bx * ry - by * rx  # back x right
    return np.array([[rx, ry, rz], [ux, uy, uz], [bx, by, bz]])


@dataclass(frozen=True)
class Cascade:
    view: np.ndarray  # (4, 4) float32: render-relative positions -> the light's view
    projection: np.ndarray  # (4, 4) float32: reverse-Z orthographic, the square around the sphere
    radius: float  # of the slice's sphere: the map covers 2 * radius across
    texel: float  # world units per shadow-map texel
    near: float  # the slice's view distances
    far: float

    @property
    def view_projection(self) -> np.ndarray:
        return self.projection @ self.view


def view_slice_sphere(projection: np.ndarray, d0: float, d1: float) -> tuple[float, float]:
    """(distance of the centre along the view axis, radius) of the sphere around the slice
    [d0, d1] of a camera's view, perspective or orthographic, from its projection matrix
    (maths/camera.py's: symmetric, reverse-Z)."""
    p = np.asarray(projection, np.float64)
    if p[3, 3] == 1.0:  # orthographic: a box of fixed cross-section
        half_w, half_h = 1.0 / abs(p[0, 0]), 1.0 / abs(p[1, 1])
        return 0.5 * (d0 + d1), math.sqrt(half_w * half_w + half_h * half_h + 0.25 * (d1 - d0) ** 2)
    tan_half_fov_y = 1.0 / abs(p[1, 1])
    return slice_sphere(d0, d1, tan_half_fov_y, abs(p[1, 1]) / abs(p[0, 0]))


def fit_cascade(
    centre: np.ndarray,
    radius: float,
    origin: np.ndarray,
    direction: np.ndarray,
    resolution: int,
    caster_reach: float = 0.0,
    near: float = 0.0,
    far: float = 0.0,
) -> Cascade:
    """The cascade around the sphere (`centre` render-relative, `radius`) of a view slice from
    `near` to `far`; `origin`: the render origin in the world (float64); the light shines along
    `direction`; the map has `resolution` texels across. Casters up to `caster_reach` beyond
    the sphere towards the light still cast into it (the depth range grows that way; what lies
    behind the sphere casts nothing into it)."""
    return fit_cascades(
        np.reshape(centre, (1, 3)), [radius], origin, direction, resolution, caster_reach, [near], [far]
    )[0]


def fit_cascades(
    centres: np.ndarray,
    radii: Sequence[float],
    origin: np.ndarray,
    direction: np.ndarray,
    resolution: int,
    caster_reach: float = 0.0,
    nears: Sequence[float] = (),
    fars: Sequence[float] = (),
) -> list[Cascade]:
    """`fit_cascade` for a light's C cascades at once ((C, 3) centres, C radii, nears, fars):
    one set of array operations, not one per cascade (this runs every frame)."""
    if resolution < 1:
        raise ValueError(f"a shadow map needs at least one texel, got {resolution!r}")
    for radius in radii:
        check_positive("radius", radius)
    rot = light_rotation(direction)
    origin = np.asarray(origin, np.float64).reshape(3)
    reach = max(float(caster_reach), 0.0)
    r = np.asarray(radii, np.float64)
    count = len(r)
    # each centre in the light's frame measured from the world origin, snapped to whole texels
    texel = 2.0 * r / resolution
    c = (np.asarray(centres, np.float64).reshape(count, 3) + origin) @ rot.T
    c[:, :2] = np.round(c[:, :2] / texel[:, None]) * texel[:, None]
    c[:, 2] += r + reach  # the light's eye, on the back axis
    view = np.zeros((count, 4, 4))
    view[:, :3, :3] = rot
    view[:, :3, 3] = rot @ origin - c  # float64, then the cast: render-relative input
    view[:, 3, 3] = 1.0
    projection = np.zeros((count, 4, 4))
    projection[:, 0, 0] = 1.0 / r
    projection[:, 1, 1] = -1.0 / r  # Vulkan y flip, as maths.camera.orthographic
    projection[:, 2, 2] = 1.0 / (2.0 * r + reach)  # reverse-Z: depth = (depth - d) / depth, d = -z from the eye
    projection[:, 2, 3] = 1.0
    projection[:, 3, 3] = 1.0
    view32, projection32 = view.astype(np.float32), projection.astype(np.float32)
    nears = list(nears) or [0.0] * count
    fars = list(fars) or [0.0] * count
    return [
        Cascade(
            view=view32[k],
            projection=projection32[k],
            radius=float(r[k]),
            texel=float(texel[k]),
            near=float(nears[k]),
            far=float(fars[k]),
        )
        for k in range(count)
    ]
