"""The world's queries: rays in batches, shape casts and overlaps, answered as entities."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..components.physics import BOX, PRIMITIVES, SPHERE
from ..ecs.entities import INDEX_MASK
from ..jobs import over_rows
from .ray_walk import claims

RAY_CHUNK = 1024  # rays at least per job of the library's batch (fewer cost more to wake than they save)
# rays per thread of numba's that casts them (up to the pool's thread count; fewer than twice
# this are cast on the calling thread). On the GPU host 10,000 rays on the pile right after a
# step took 3.2-4.4 ms on one thread, 1.0-1.5 on 6, 0.89-1.05 on 10 and 0.82-1.03 on 16
RAYS_PER_THREAD = 500
# a ray hit as the library packs it (48 bytes)
_HIT = np.dtype(
    [
        ("handle", np.uint64),
        ("fraction", np.float32),
        ("normal", np.float32, 3),
        ("point", np.float32, 3),
        ("sub_shape", np.uint32),
        ("material", np.uint32),
        ("pad", np.uint32),
    ]
)


@dataclass(frozen=True)
class RayHits:
    """Per ray: the `entity` hit first (-1: none), the `distance` along the ray, the hit `point`
    and the surface `normal` there (NaN where nothing was hit)."""

    entity: np.ndarray
    distance: np.ndarray
    point: np.ndarray
    normal: np.ndarray


@dataclass(frozen=True)
class ShapeHit:
    """What a shape cast touched first: the `entity`, the `distance` the shape moved before, the
    contact `point` and the surface `normal` there."""

    entity: int
    distance: float
    point: np.ndarray
    normal: np.ndarray


def raycast(physics: Any, origins: Any, directions: Any, max_distance: float) -> RayHits:
    if not (math.isfinite(max_distance) and max_distance > 0.0):
        raise ValueError(f"raycast: max_distance must be a positive finite number, got {max_distance!r}")
    o = np.ascontiguousarray(np.asarray(origins, np.float64).reshape(-1, 3))
    d = np.ascontiguousarray(np.asarray(directions, np.float64).reshape(-1, 3))
    if len(o) != len(d):
        raise ValueError(f"raycast: {len(o)} origins but {len(d)} directions")
    jobs = 1 if physics.pool is None else min(physics.pool.threads, len(o) // RAYS_PER_THREAD)
    entity, distance = np.empty(len(o), np.int64), np.empty(len(o))
    point, normal = np.empty((len(o), 3)), np.empty((len(o), 3))
    out, shared = (entity, distance, point, normal), claims()

    def refresh_and_cast(grid: Any, everything: bool) -> bool:
        return grid.refresh_and_cast(everything, jobs, o, d, max_distance, out, shared, grid.shapes.entity)

    with physics.ray_lock:
        grid, others = physics.ray_grid(refresh_and_cast if jobs > 1 else None)
        if grid is None:  # without numba: the library's batch answers every ray
            return _library_rays(physics, o, _unit(o, d), max_distance)
        if shared[0] < len(o):  # (not cast with the grid's refresh)
            grid.cast(o, d, max_distance, out, shared, grid.shapes.entity, jobs)
    if len(o) and entity.min() == -2:
        _unit(o, d)  # (the error naming the first such ray)
    if others:  # mesh, hull and terrain bodies are the library's to cast against
        theirs = _library_rays(physics, o, _unit(o, d), max_distance)
        shape = physics.bodies.spec["shape"][np.where(theirs.entity >= 0, theirs.entity & INDEX_MASK, 0)]
        nearer = (theirs.entity >= 0) & ~np.isin(shape, PRIMITIVES) & ~(distance <= theirs.distance)
        entity[nearer], distance[nearer] = theirs.entity[nearer], theirs.distance[nearer]
        point[nearer], normal[nearer] = theirs.point[nearer], theirs.normal[nearer]
    return RayHits(entity, distance, point, normal)


def _unit(o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The rays' directions made unit length, or ValueError naming the first ray that is not
    finite or has no direction."""
    finite = np.isfinite(o).all(axis=1) & np.isfinite(d).all(axis=1)
    if not finite.all():
        raise ValueError(f"raycast: origins and directions must be finite (ray {int(np.argmin(finite))} is not)")
    length = np.linalg.norm(d, axis=1)
    if len(d) and length.min() == 0.0:
        raise ValueError(f"raycast: direction {int(np.argmin(length))} has zero length")
    return d / length[:, None] if len(d) else d


def _library_rays(physics: Any, o: np.ndarray, unit: np.ndarray, max_distance: float) -> RayHits:
    """The rays cast by the library's batch (float32), in chunks over the world's JobPool."""
    starts, toward, hits = o.astype(np.float32), unit.astype(np.float32), np.empty(len(o), _HIT)

    def cast(rows: slice) -> None:
        raw = physics.native.raycast_batch(starts[rows].ravel(), toward[rows].ravel(), float(max_distance))
        hits[rows] = np.frombuffer(raw, _HIT)

    over_rows(physics.pool, len(o), cast, RAY_CHUNK)
    entity = physics.bodies.entities_of(hits["handle"])
    hit = entity >= 0
    distance = np.where(hit, hits["fraction"].astype(np.float64) * max_distance, np.nan)
    point = np.where(hit[:, None], o + unit * distance[:, None], np.nan)
    normal = np.where(hit[:, None], hits["normal"].astype(np.float64), np.nan)
    return RayHits(entity, distance, point, normal)


def _vector(value: Any, name: str, what: str) -> tuple[float, ...]:
    v = np.asarray(value, np.float64).reshape(-1)
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ValueError(f"{what}: {name} must be 3 finite numbers, got {value!r}")
    return tuple(v.tolist())


def _extent(shape: int, size: Any, what: str) -> Any:
    """A Collider's size as the library takes this shape's (bodies.py does the same)."""
    s = np.broadcast_to(np.asarray(size, np.float64), (3,)) if np.ndim(size) == 0 else np.asarray(size, np.float64)
    if shape not in PRIMITIVES:
        raise ValueError(f"{what}: shape must be BOX, SPHERE, CAPSULE or CYLINDER, got {shape}")
    if s.shape != (3,) or not np.isfinite(s).all() or (s <= 0).any():
        raise ValueError(f"{what}: size must be 3 positive finite numbers, got {size!r}")
    if shape == BOX:
        return tuple(s.tolist())
    if shape == SPHERE:
        return float(s[0])
    return (float(s[1]), float(s[0]))


def shapecast(
    physics: Any, shape: int, size: Any, origin: Any, motion: Any, rotation: Any, ignore: int
) -> ShapeHit | None:
    from .bodies import SHAPES

    extent = _extent(shape, size, "shapecast")
    start, move = _vector(origin, "origin", "shapecast"), _vector(motion, "motion", "shapecast")
    turn = np.asarray(rotation, np.float64).reshape(-1)
    if turn.shape != (4,) or not np.isfinite(turn).all() or not np.linalg.norm(turn) > 0:
        raise ValueError(f"shapecast: rotation must be a non-zero quaternion, got {rotation!r}")
    skip = physics.bodies.handle_of(ignore) if ignore >= 0 else None
    kind = getattr(physics.lib, SHAPES[shape])
    found = physics.native.shapecast(
        kind, start, tuple((turn / np.linalg.norm(turn)).tolist()), move, extent, skip or 0
    )
    if found is None:
        return None
    handle, fraction, point, normal = found
    entity = int(physics.bodies.entities_of(np.array([handle], np.uint64))[0])
    if entity < 0:
        return None
    return ShapeHit(entity, float(fraction) * math.dist(move, (0.0, 0.0, 0.0)), np.array(point), np.array(normal))


def overlap_sphere(physics: Any, centre: Any, radius: float) -> np.ndarray:
    if not (math.isfinite(radius) and radius > 0.0):
        raise ValueError(f"overlap_sphere: radius must be a positive finite number, got {radius!r}")
    found = physics.native.overlap_sphere(_vector(centre, "centre", "overlap_sphere"), float(radius))
    return _ours(physics, found)


def overlap_box(physics: Any, low: Any, high: Any) -> np.ndarray:
    lo, hi = _vector(low, "low", "overlap_box"), _vector(high, "high", "overlap_box")
    if any(a > b for a, b in zip(lo, hi)):
        raise ValueError(f"overlap_box: low {lo} must not be above high {hi}")
    return _ours(physics, physics.native.overlap_aabb(lo, hi))


def _ours(physics: Any, handles: list[int]) -> np.ndarray:
    entities = physics.bodies.entities_of(np.asarray(handles, np.uint64))
    return np.sort(entities[entities >= 0])
