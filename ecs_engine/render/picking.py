"""Which entity is under a pixel: a ray from the active camera through the pixel, tested against
every drawn entity's bounding sphere (vectorised over all of them), then against the triangles of
the meshes whose spheres it enters, nearest sphere first, until no sphere can hold a nearer hit.

Chosen over an id buffer (a GPU pass writing entity ids, read back): the ray needs no extra pass,
no GPU round trip and no frame of latency, works headless and between frames, and gives the hit
point and distance too. Its cost grows with the entities (the sphere test: one NumPy pass over
the ModelMatrix column) and with the triangles of the few meshes whose spheres the ray enters.

The test is what the renderer draws: ModelMatrix (render-relative float32) and the mesh's
triangles, double-sided (a click on a back face still picks); a skinned or morphed mesh's
triangles posed as its vertex shader poses them (the pose's sphere first, as for culling).
Entities without Mesh, or with a handle the registry lacks, are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import native
from ..animation.skins import Skins, skinned_positions
from ..components import Mesh, ModelMatrix, render_origin
from ..components.animation import MorphWeights, Skinned
from ..ecs.world import World
from .frame.camera import camera_matrices


@dataclass(frozen=True)
class Pick:
    """The nearest hit: the entity, the point in the world (float64) and its distance."""

    entity: int
    point: np.ndarray
    distance: float


Region = tuple[float, float, float, float]  # x0, y0, x1, y1: fractions of the target (camera.py)


def pixel_ray(
    world: World, x: float, y: float, width: float, height: float, region: Region | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The ray through pixel (x, y) (from the top left; pixel centres at .5) of a width x height
    target showing the active camera (in `region` of it, as the renderer's region): origin
    (world, float64) and unit direction."""
    cam = camera_matrices(world, width / height, region)
    inverse = np.linalg.inv(cam.projection.astype(np.float64))
    ndc_x, ndc_y = x / width * 2.0 - 1.0, y / height * 2.0 - 1.0
    # reverse-Z: depth 1 is the near plane; 0.5 is finite for every projection the engine makes
    points = np.array([[ndc_x, ndc_y, 1.0, 1.0], [ndc_x, ndc_y, 0.5, 1.0]]) @ inverse.T
    points = points[:, :3] / points[:, 3:]
    rotation = np.asarray(cam.inverse_view, np.float64)[:3, :3]
    near, far = points @ rotation.T
    direction = far - near
    return np.asarray(cam.position, np.float64) + near, direction / np.linalg.norm(direction)


def _rows(world: World) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ids, models, handles = [], [], []
    for batch in world.query(Mesh, ModelMatrix, write=()):
        ids.append(batch.entities)
        models.append(batch[ModelMatrix].model)
        handles.append(batch[Mesh].handle)
    if not ids:
        return np.empty(0, np.int64), np.empty((0, 4, 4), np.float32), np.empty(0, np.uint32)
    return np.concatenate(ids), np.concatenate(models), np.concatenate(handles)


@native.njit
def _entries_native(origin, direction, models, centers, radii, handles, out):  # pragma: no cover - compiled
    for n in range(models.shape[0]):
        h = handles[n]
        c = centers[h]
        m = models[n]
        scale2 = 0.0
        for col in range(3):
            s = m[0, col] * m[0, col] + m[1, col] * m[1, col] + m[2, col] * m[2, col]
            scale2 = max(scale2, s)
        radius = radii[h] * np.sqrt(scale2)
        along = 0.0
        dist2 = 0.0
        for row in range(3):
            center = m[row, 0] * c[0] + m[row, 1] * c[1] + m[row, 2] * c[2] + m[row, 3]
            d = center - origin[row]
            along += d * direction[row]
            dist2 += d * d
        inside2 = radius * radius - (dist2 - along * along)
        if inside2 < 0.0:
            out[n] = np.inf
            continue
        root = np.sqrt(inside2)
        out[n] = np.inf if along + root < 0.0 else max(along - root, 0.0)


def _sphere_entries(
    origin: np.ndarray, direction: np.ndarray, models: np.ndarray, centers: np.ndarray, radii: np.ndarray
) -> np.ndarray:
    """Per row, the ray's distance to where it enters the row's bounding sphere (inf: missed;
    0 when the origin is inside). Model matrices are [row, column]: p' = M[:3, :3] p + M[:3, 3].
    (The NumPy form; `_rows_entries` runs the compiled one over the columns without copies.)"""
    m = models.astype(np.float64)
    linear = m[:, :3, :3]
    center = np.einsum("nij,nj->ni", linear, centers) + m[:, :3, 3]
    radius = radii * np.sqrt(np.max(np.sum(linear * linear, axis=1), axis=1))  # the largest column
    to_center = center - origin
    along = to_center @ direction
    gap2 = np.einsum("ni,ni->n", to_center, to_center) - along * along
    inside2 = radius * radius - gap2
    entry = along - np.sqrt(np.maximum(inside2, 0.0))
    hit = (inside2 >= 0.0) & (along + np.sqrt(np.maximum(inside2, 0.0)) >= 0.0)
    return np.where(hit, np.maximum(entry, 0.0), np.inf)


def ray_triangles(origin: np.ndarray, direction: np.ndarray, triangles: np.ndarray) -> float:
    """The nearest t >= 0 where origin + t direction crosses one of `triangles` (T, 3, 3),
    either side (Moller-Trumbore, vectorised), or inf."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.einsum("ti,ti->t", e1, p)
    ok = np.abs(det) > 1e-12 * np.maximum(np.einsum("ti,ti->t", e1, e1), 1e-30)
    inverse = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin - a
    u = np.einsum("ti,ti->t", s, p) * inverse
    q = np.cross(s, e1)
    v = (q @ direction) * inverse
    t = np.einsum("ti,ti->t", e2, q) * inverse
    hit = ok & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t >= 0.0)
    return float(t[hit].min()) if hit.any() else float("inf")


def _rows_entries(
    world: World, origin: np.ndarray, direction: np.ndarray, centers: np.ndarray, radii: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Ids, models, handles and sphere entries of the rows whose spheres the ray enters."""
    if not native.AVAILABLE:
        ids, models, handles = _rows(world)
        known = handles < len(radii)
        ids, models, handles = ids[known], models[known], handles[known].astype(np.int64)
        entries = _sphere_entries(origin, direction, models, centers[handles], radii[handles])
        hit = np.isfinite(entries)
        return ids[hit], models[hit], handles[hit], entries[hit]
    parts: list[tuple[np.ndarray, ...]] = []
    for batch in world.query(Mesh, ModelMatrix, write=()):
        handles = batch[Mesh].handle.astype(np.int64)
        known = handles < len(radii)
        models = batch[ModelMatrix].model
        ids = batch.entities
        if not known.all():
            handles, models, ids = handles[known], models[known], ids[known]
        entries = np.empty(len(ids))
        _entries_native(origin, direction, models, centers, radii, handles, entries)  # type: ignore[misc]
        hit = np.flatnonzero(np.isfinite(entries))
        parts.append((ids[hit], models[hit], handles[hit], entries[hit]))
    if not parts:
        return np.empty(0, np.int64), np.empty((0, 4, 4), np.float32), np.empty(0, np.int64), np.empty(0)
    return tuple(np.concatenate(p) for p in zip(*parts))  # type: ignore[return-value]


def pick(
    world: World,
    meshes: Any,
    x: float,
    y: float,
    width: float,
    height: float,
    region: Region | None = None,
) -> Pick | None:
    """The entity drawn nearest under pixel (x, y) of a width x height target (showing the view in
    `region` of it, as the renderer's region), or None. `meshes` is the renderer's MeshRegistry
    (bounds() and [handle].data)."""
    origin, direction = pixel_ray(world, x, y, width, height, region)
    centers, radii, _ = meshes.bounds()
    local_origin = origin - render_origin(world)  # ModelMatrix is relative to the render origin
    ids, models, handles, entries = _rows_entries(world, local_origin, direction, centers, radii)
    if not len(ids):
        return None
    best_t, best = float("inf"), -1
    for row in np.argsort(entries, kind="stable"):
        if entries[row] >= best_t:  # every later sphere starts beyond the nearest hit so far
            break
        data = meshes[int(handles[row])].data
        triangles = _triangles(world, int(ids[row]), data, models[row].astype(np.float64), origin - local_origin)
        t = ray_triangles(local_origin, direction, triangles)
        if t < best_t:
            best_t, best = t, row
    if best < 0:
        return None
    return Pick(int(ids[best]), origin + best_t * direction, best_t)


def _triangles(world: World, entity: int, data: Any, model: np.ndarray, render_at: np.ndarray) -> np.ndarray:
    """A row's triangles (T, 3, 3) relative to the render origin `render_at`, as the vertex
    shaders place them (shaders/deform.glsl): a morphed mesh's vertices moved by its weights, then
    a skinned mesh's posed by its copy's joints (its ModelMatrix only places a bounding sphere
    around the pose), else the model matrix's."""
    positions = data.positions.astype(np.float64)
    morph = getattr(data, "morph", None)
    if morph is not None and world.has(entity, MorphWeights):
        positions = morph.applied(world.get(entity, MorphWeights).weights, positions, data.normals)[0]
    skin: Any = getattr(data, "skin", None)
    skins = world.resources.get(Skins) if skin is not None and world.has(entity, Skinned) else None
    if skins is not None:
        handle, copy = int(world.get(entity, Skinned).skin), int(world.get(entity, Skinned).copy)
        posed = skins[handle] if 0 <= handle < len(skins) else None
        if posed is not None and posed.matrices is not None and copy < posed.copies:
            moved = skinned_positions(positions, skin.joints, skin.weights, posed.world_matrices(copy)) - render_at
            return moved[data.indices.reshape(-1, 3)]
    return positions[data.indices.reshape(-1, 3)] @ model[:3, :3].T + model[:3, 3]
