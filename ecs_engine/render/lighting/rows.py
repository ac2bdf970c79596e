"""Light rows for the per-frame light buffer (layouts.LIGHT, 16 floats a light).

Point and spot lights come first: position relative to the render origin (float64 difference,
then the cast), radius, colour, intensity, the direction a spot light shines and its cone, sorted
far to near from the camera (their billboards blend back to front). Directional lights follow,
in world order.

A numba kernel writes the positional rows straight into the mapped buffer in one call; the NumPy
reference gives the same rows. The kernel exists for small scenes: the NumPy version's dozen array
operations cost ~25 us a frame for 8 lights, a tenth of the 100-cube frame's budget.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ... import native
from ..layouts import (
    FEATURE_DIRECTIONAL_LIGHTS,
    FEATURE_SPOT_LIGHTS,
    LIGHT,
    LIGHT_DIRECTIONAL,
    LIGHT_POINT,
    LIGHT_SPOT,
    RAY_PLACE,
)

LIGHT_DTYPE = LIGHT.dtype
FLOATS = 16  # a light's row seen as float32s
if not (
    LIGHT.size == 4 * FLOATS
    and [LIGHT.offset(n) for n in ("position_radius", "color_intensity", "direction_kind", "cone")] == [0, 16, 32, 48]
):
    raise RuntimeError(f"the light kernel assumes 16 floats a light in this order:\n{LIGHT.glsl()}")
NO_CONE = (-2.0, 0.0)  # cos(outer) below -1: every direction is inside


@dataclass
class PositionalLights:
    """One table's point or spot lights: views into the world's columns, or arrays made for the frame."""

    position: np.ndarray  # (n, 3) float64
    radius: np.ndarray  # (n,)
    color: np.ndarray  # (n, 3)
    intensity: np.ndarray  # (n,)
    direction: np.ndarray | None = None  # (n, 3) where a spot light shines; None: point lights
    cone: np.ndarray | None = None  # (n, 2): cos(outer), 1 / (cos(inner) - cos(outer))
    entity: np.ndarray | None = None  # (n,) the lights' entities (shadows name their views by them)
    # the kernel's columns, kept when they are these views themselves (extract_lights keeps a
    # table's point lights from frame to frame, and the views see new values)
    kernel_columns: tuple[np.ndarray, ...] | None = field(default=None, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.radius)


@dataclass
class DirectionalLights:
    direction: np.ndarray  # (n, 3): where the light shines
    color: np.ndarray  # (n, 3)
    illuminance: np.ndarray  # (n,)
    entity: np.ndarray | None = None  # (n,)

    def __len__(self) -> int:
        return len(self.illuminance)


def light_features(positional: list[PositionalLights], directional: list[DirectionalLights]) -> int:
    """The FEATURE_* bits of the light kinds present: the mesh shaders read only those."""
    features = 0
    for p in positional:
        if p.direction is not None and len(p):
            features |= FEATURE_SPOT_LIGHTS
            break
    for d in directional:
        if len(d):
            features |= FEATURE_DIRECTIONAL_LIGHTS
            break
    return features


def local_minus_z(rotation: np.ndarray) -> np.ndarray:
    """Where unit quaternions (n, 4), (x, y, z, w), turn the local -Z axis: -(third column)."""
    x, y, z, w = (rotation[:, k] for k in range(4))
    return -np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=1)


def spot_cones(inner: np.ndarray, outer: np.ndarray) -> np.ndarray:
    """(n, 2) rows of (cos(outer), 1 / (cos(inner) - cos(outer))), as KHR_lights_punctual's
    reference shader: the falloff is clamp((cos - cos_outer) * scale, 0, 1)^2."""
    cos_outer = np.cos(np.asarray(outer, np.float64))
    cos_inner = np.cos(np.asarray(inner, np.float64))
    return np.stack([cos_outer, 1.0 / np.maximum(cos_inner - cos_outer, 1e-4)], axis=1)


def far_to_near(position: np.ndarray, origin: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """The order of the positional rows: far to near from `eye` (relative to `origin`), ties in
    world order (the kernel below sorts the same way, stably)."""
    to_eye = position - np.asarray(origin, np.float64) - np.asarray(eye, np.float64)
    return np.argsort(-np.einsum("ij,ij->i", to_eye, to_eye), kind="stable")


def write_positional_numpy(
    position: np.ndarray,
    radius: np.ndarray,
    color: np.ndarray,
    intensity: np.ndarray,
    direction: np.ndarray,
    cone: np.ndarray,
    kind: np.ndarray,
    origin: np.ndarray,
    eye: np.ndarray,
    out: np.ndarray,
) -> None:
    """Reference version of the positional kernel: `out` is (n, 16) float32."""
    rel = position - origin
    order = far_to_near(position, origin, eye)
    out[:, :3] = rel[order]
    out[:, 3] = radius[order]
    out[:, 4:7] = color[order]
    out[:, 7] = intensity[order]
    out[:, 8:11] = direction[order]
    out[:, 11] = kind[order]
    out[:, 12:14] = cone[order]
    out[:, 14:] = 0


def _write_positional_kernel(
    position, radius, color, intensity, direction, cone, kind, origin, eye, out
):  # pragma: no cover
    n = position.shape[0]
    minus_dist = np.empty(n)
    for i in range(n):
        d = 0.0
        for c in range(3):
            v = position[i, c] - origin[c] - eye[c]
            d += v * v
        minus_dist[i] = -d
    order = np.argsort(minus_dist, kind="mergesort")  # stable
    for j in range(n):
        i = order[j]
        for c in range(3):
            out[j, c] = position[i, c] - origin[c]
            out[j, 4 + c] = color[i, c]
            out[j, 8 + c] = direction[i, c]
        out[j, 3] = radius[i]
        out[j, 7] = intensity[i]
        out[j, 11] = kind[i]
        out[j, 12] = cone[i, 0]
        out[j, 13] = cone[i, 1]
        out[j, 14] = 0.0
        out[j, 15] = 0.0


_write_positional_native = native.njit(_write_positional_kernel)


_Columns = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


_POINT_COLUMNS: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _point_columns(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Direction, cone and kind columns of n point lights: made once per count and kept (read
    only), since allocating them each frame cost a small scene ~30 us (measured on the H100 host:
    the model scene's CPU frame went from 0.20 to 0.29 ms with materials)."""
    found = _POINT_COLUMNS.get(n)
    if found is None:
        if len(_POINT_COLUMNS) > 64:
            _POINT_COLUMNS.clear()
        found = (
            np.zeros((n, 3)),
            np.ascontiguousarray(np.broadcast_to(NO_CONE, (n, 2))),
            np.full(n, LIGHT_POINT, np.float32),
        )
        for array in found:
            array.flags.writeable = False
        _POINT_COLUMNS[n] = found
    return found


def _columns(parts: list[PositionalLights]) -> _Columns:
    """The parts' columns, concatenated (a single part's are used as they are)."""
    directions: list[np.ndarray] = []
    cones: list[np.ndarray] = []
    kinds: list[np.ndarray] = []
    for p in parts:
        if p.direction is None or p.cone is None:
            direction, cone, kind = _point_columns(len(p))
        else:
            direction, cone, kind = p.direction, p.cone, np.full(len(p), LIGHT_SPOT, np.float32)
        directions.append(direction)
        cones.append(cone)
        kinds.append(kind)
    if len(parts) == 1:
        p = parts[0]
        return p.position, p.radius, p.color, p.intensity, directions[0], cones[0], kinds[0]
    return (
        np.concatenate([p.position for p in parts]),
        np.concatenate([p.radius for p in parts]),
        np.concatenate([p.color for p in parts]),
        np.concatenate([p.intensity for p in parts]),
        np.concatenate(directions),
        np.concatenate(cones),
        np.concatenate(kinds),
    )


def _kernel_columns(parts: list[PositionalLights]) -> _Columns:
    """_columns, each C-contiguous (the kernel's one compiled layout); a single part's kept on it
    when no column had to be copied."""
    if len(parts) == 1:
        kept = parts[0].kernel_columns
        if kept is not None:
            return kept  # type: ignore[return-value]
    columns = _columns(parts)
    contiguous = tuple([c if c.flags.c_contiguous else np.ascontiguousarray(c) for c in columns])
    if len(parts) == 1 and all(a is b for a, b in zip(contiguous, columns, strict=True)):
        parts[0].kernel_columns = contiguous
    return contiguous  # type: ignore[return-value]


def write_lights(
    positional: list[PositionalLights],
    directional: list[DirectionalLights],
    origin: np.ndarray,
    eye: np.ndarray,
    out: np.ndarray,
) -> int:
    """Write every light into `out`, a (total, 16) float32 array (LIGHT_DTYPE rows seen as
    floats): point and spot lights relative to `origin`, sorted by distance from `eye` (relative
    to `origin`), far first; then the directional ones. Returns the positional count."""
    origin = np.asarray(origin, dtype=np.float64)
    eye = np.asarray(eye, dtype=np.float64)
    count = 0
    if positional:
        if _write_positional_native is None:
            columns = _columns(positional)
            count = len(columns[1])
            if count:
                write_positional_numpy(*columns, origin, eye, out[:count])
        else:
            columns = _kernel_columns(positional)
            count = len(columns[1])
            if count:
                _write_positional_native(*columns, origin, eye, out[:count])
    row = count
    for d in directional:
        rows = out[row : row + len(d)]
        rows[:] = 0
        rows[:, 4:7] = d.color
        rows[:, 7] = d.illuminance
        rows[:, 8:11] = d.direction
        rows[:, 11] = LIGHT_DIRECTIONAL
        row += len(d)
    return count


def write_light_shadows(
    positional: list[PositionalLights],
    directional: list[DirectionalLights],
    eye_from_origin: np.ndarray,
    origin: np.ndarray,
    views: dict[int, tuple[int, int]],
    out: np.ndarray,
    places: dict[int, int] | None = None,
) -> None:
    """Name each shadow-casting light's views in its row (cone.z: first view + 1, cone.w: the
    count), `views` mapping a light's entity to (first view, count), and its place in the
    ray-traced shadows' mask (`places`: entity to place; cone.w += RAY_PLACE * (place + 1)).
    Positional rows are in write_lights' order (far to near from the eye, ties in world order),
    found again here."""
    places = places or {}
    count = sum(len(p) for p in positional)
    if count:
        entity = np.concatenate([p.entity for p in positional if p.entity is not None])
        order = far_to_near(np.concatenate([p.position for p in positional]), origin, eye_from_origin)
        for row, e in enumerate(entity[order].tolist()):
            _name(out, row, views.get(e), places.get(e))
    row = count
    for d in directional:
        for e in d.entity.tolist() if d.entity is not None else [None] * len(d):
            if e is not None:
                _name(out, row, views.get(e), places.get(e))
            row += 1


def _name(out: np.ndarray, row: int, views: tuple[int, int] | None, place: int | None) -> None:
    if views is None and place is None:
        return  # a light that casts no shadow: cone.z and cone.w stay 0
    first, count = views if views is not None else (-1, 0)
    out[row, 14:16] = (first + 1, count + (0 if place is None else RAY_PLACE * (place + 1)))
