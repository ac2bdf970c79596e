"""Levels of detail made at load: coarser copies of a mesh by quadric-error edge collapse (the
fast-simplification library), each with its geometric error, and the rule that picks a level from
that error projected to the screen, in NumPy, as the culling shader does it per row.

Level 0 is the mesh itself (error 0); `build_lods` makes the coarser ones. A level's error is a
distance in the mesh's own units (before an entity's scale): how far its surface strays from the
original's, measured both ways at vertices (lod_error.py). A level is good enough while that
error covers under about a pixel on screen, so `lod_for_screen_size` takes the coarsest level whose
error, projected at the nearest point of the bounding sphere, is at most `threshold_px`.

A skinned or morphed mesh's levels keep its joints, weights and morph deltas: each level vertex
takes those of the original vertex it is (see below), so the vertex shader poses a level as it
poses the mesh. Their error also bounds what the collapses get wrong once the mesh moves
(lod_deform.py), which its rest shape does not show.

Why the attributes are chosen, not interpolated: the library moves kept vertices to their quadric's
optimum and returns only positions and triangles. Split vertices (UV seams, hard edges) would tear
the surface if simplified apart, so positions are welded first; every output vertex is a welded
original vertex that survived its collapses, and each corner takes the normal and UV of that
survivor's own split copy closest (in UV and normal) to the corner's original copy. Seams and hard
edges that survive stay sharp, the shading keeps the detailed mesh's normals, and no vertex gets
an average of two sides of a seam. A carried normal facing away from the new surface (more than
90° from its faces' normal) is replaced by that face normal. Tangents are made again from the UVs.

LOD meshes have `source` None: they are remade from their base mesh at load, never saved."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import Final

import fast_simplification
import numpy as np

from .lod_deform import deform_error, joint_regions
from .lod_error import level_error
from .mesh_data import MeshData

__all__ = [
    "DEFAULT_RATIOS",
    "MAX_VALENCE_SQUARES",
    "MIN_TRIANGLES",
    "Lod",
    "build_lods",
    "focal_pixels",
    "lod_errors",
    "lod_for_screen_size",
]

#: Fractions of the original triangles the levels aim for: each halves the last.
DEFAULT_RATIOS: Final = (0.5, 0.25, 0.125)
#: No level under this many triangles: a smaller mesh costs the GPU about its draw, not its triangles
#: (a cube, 12 triangles, gets no levels).
MIN_TRIANGLES: Final = 64
#: A level must have at least this fraction fewer triangles than the one before, or the levels stop
#: (the library could not collapse further without flipping faces or tearing borders).
MIN_DROP: Final = 0.1
# Twice a triangle's area below this fraction of the mesh's squared size: no normal, so no quadric
# (the library would divide by zero); as mesh_loading.py drops such triangles from files.
_DEGENERATE_AREA: Final = 1e-12
#: No levels for a mesh whose vertices' triangle counts, squared, add up past this: the library's
#: time grows with the square of a vertex's triangles (a fan around one vertex: 0.07 s a level at
#: 10k triangles, 3.9 s at 80k; a 5.7 MB OBJ of a 100k-triangle fan passed 10 s). Ordinary meshes
#: sum about 36 a vertex (a million-vertex UV sphere: 4e7); this allows about 0.6 s a level.
MAX_VALENCE_SQUARES: Final = 1 << 30
# A moved corner takes the best of at most this many copies of its survivor (a UV sphere at the
# scene-file recipe cap has 512 at each pole).
_COPIES_SEARCHED: Final = 1024
# The library keeps the mesh it works on in module state: one simplification at a time.
_LIBRARY_LOCK = threading.Lock()


@dataclass(frozen=True)
class Lod:
    """One coarser level: its mesh, its error (object-space units, before the entity's scale; 0 is
    exact) and the fraction of the original triangles it was asked for."""

    mesh: MeshData
    error: float
    ratio: float


@dataclass(frozen=True)
class _Welded:
    """The mesh with split vertices merged by position, and its usable triangles."""

    positions: np.ndarray  # (W, 3) float64
    weld: np.ndarray  # (V,) render vertex -> welded vertex
    triangles: np.ndarray  # (T, 3) welded indices, degenerate triangles dropped
    corners: np.ndarray  # (T, 3) the same triangles' render vertices


def build_lods(
    mesh: MeshData, ratios: Sequence[float] = DEFAULT_RATIOS, min_triangles: int = MIN_TRIANGLES
) -> list[Lod]:
    """Coarser levels of `mesh`, finest first, each aiming for `ratio` times its triangles (each
    simplified from the original, not from the level before, so errors do not compound).

    The levels stop at the first that would have fewer than `min_triangles` triangles, or fewer
    than MIN_DROP (10%) fewer than the level before. Errors never decrease from one level to the
    next (a level's is at least the one before's), so a selection rule can rely on their order.

    Degenerate triangles (repeated vertices, no area) are left out of the simplification; a mesh
    with none left, like an empty one, gets no levels ([]), nor does one with vertices shared by
    very many triangles (fans: MAX_VALENCE_SQUARES). A MeshData cannot hold NaN or infinite
    positions (its constructor refuses them); should the library return any, that level and the
    coarser ones are not made. Bad `ratios` (not strictly decreasing within (0, 1)) or
    `min_triangles` (under 1) raise ValueError, anything but a MeshData TypeError."""
    if not isinstance(mesh, MeshData):
        raise TypeError(f"build_lods needs a MeshData, got {type(mesh).__name__}")
    ratios = [float(r) for r in ratios]
    if any(not 0.0 < r < 1.0 for r in ratios) or any(a <= b for a, b in pairwise(ratios)):
        raise ValueError(f"LOD ratios must be strictly decreasing fractions in (0, 1), got {ratios}")
    if isinstance(min_triangles, bool) or not isinstance(min_triangles, (int, np.integer)) or min_triangles < 1:
        raise ValueError(f"min_triangles must be an integer of at least 1, got {min_triangles!r}")
    regions = joint_regions(mesh)  # a skinned mesh is simplified within each joint's region
    if regions is not None:
        mesh = regions[0]
    welded = _welded(mesh, None if regions is None else regions[1])
    valence = np.bincount(welded.triangles.reshape(-1)).astype(np.float64)
    if float((valence * valence).sum()) > MAX_VALENCE_SQUARES:
        return []
    total = len(welded.triangles)
    levels: list[Lod] = []
    previous, error = total, 0.0
    for i, ratio in enumerate(ratios, start=1):
        target = int(ratio * total)
        if target < min_triangles:
            break
        level = _simplified(mesh, welded, target, f"{mesh.name} lod{i}", keep_borders=regions is not None)
        if level is None:
            break
        lod_mesh, level_error = level
        count = lod_mesh.triangle_count
        if count < min_triangles or count > (1.0 - MIN_DROP) * previous:
            break
        error = max(error, level_error)
        levels.append(Lod(lod_mesh, error, ratio))
        previous = count
    return levels


def lod_errors(lods: Sequence[Lod]) -> np.ndarray:
    """The errors of level 0 (the mesh itself: 0) and of `lods`, as `lod_for_screen_size` takes them."""
    return np.array([0.0, *(lod.error for lod in lods)], dtype=np.float32)


def focal_pixels(fov_y: float, viewport_height: float) -> float:
    """Pixels a length of 1 spans at distance 1 straight ahead: a perspective camera with vertical
    field of view `fov_y` (radians) over `viewport_height` pixels. A length s at distance d spans
    about s * focal / d pixels."""
    if not 0.0 < fov_y < np.pi or not viewport_height > 0:
        raise ValueError(f"need 0 < fov_y < pi and viewport_height > 0, got {fov_y}, {viewport_height}")
    return float(viewport_height / (2.0 * np.tan(fov_y / 2.0)))


def lod_for_screen_size(
    errors: np.ndarray,
    distance: np.ndarray,
    radius: np.ndarray | float,
    focal_px: float,
    scale: np.ndarray | float = 1.0,
    threshold_px: float = 1.0,
) -> np.ndarray:
    """Per row, the coarsest level whose error would span at most `threshold_px` pixels.

    `errors`: (L,) for every row, or (N, L) per row, as `lod_errors` gives them (level 0 first,
    never decreasing; pad a mesh with fewer levels with inf). `distance`: (N,) from the camera to
    each bounding sphere's centre, `radius` its radius and `scale` the entity's largest scale
    (world units), `focal_px` from `focal_pixels`. The error is projected at the sphere's nearest
    point, so no part of the mesh is drawn coarser than the rule allows; a camera inside the sphere
    gets level 0. The shader's loop: level = number of levels with error * scale * focal_px <=
    threshold_px * nearest, minus one. Returns (N,) int32."""
    d = np.asarray(distance, dtype=np.float64).reshape(-1)
    e = np.asarray(errors, dtype=np.float64)
    if e.ndim == 1:
        e = e[None, :]
    if e.ndim != 2 or e.shape[1] == 0 or e.shape[0] not in (1, d.size):
        raise ValueError(f"errors must be (L,) or (N, L) with N = {d.size} rows, got shape {np.shape(errors)}")
    nearest = np.maximum(d - np.asarray(radius, dtype=np.float64).reshape(-1), 0.0)
    projected = e * (np.asarray(scale, dtype=np.float64).reshape(-1, 1) * focal_px)
    fits = projected <= threshold_px * nearest[:, None]
    return np.maximum(fits.sum(axis=1) - 1, 0).astype(np.int32)


def _welded(mesh: MeshData, region: np.ndarray | None = None) -> _Welded:
    """Merge vertices at the same position (split by UV seams or hard edges) so the simplifier
    sees one connected surface, and drop triangles with no area. With `region` (per vertex),
    only vertices of the same region merge (lod_deform.py's joint regions)."""
    positions = mesh.positions + np.float32(0.0)  # -0.0 becomes 0.0, so equal positions have equal bytes
    if region is not None:
        positions = np.c_[positions, region.astype(np.float32)]  # (joint numbers are exact in float32)
    keys = np.ascontiguousarray(positions).view(np.dtype((np.void, positions.itemsize * positions.shape[1])))
    keys = keys.reshape(-1)
    _, first, weld = np.unique(keys, return_index=True, return_inverse=True)
    weld = weld.reshape(-1)
    points = positions[first, :3].astype(np.float64)
    corners = mesh.indices.reshape(-1, 3).astype(np.int64)
    triangles = weld[corners]
    a, b, c = (points[triangles[:, k]] for k in range(3))
    double_area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    size = float(np.ptp(points, axis=0).max()) if len(points) else 0.0
    keep = (
        (triangles[:, 0] != triangles[:, 1])
        & (triangles[:, 1] != triangles[:, 2])
        & (triangles[:, 2] != triangles[:, 0])
        & (double_area > _DEGENERATE_AREA * size * size)
    )
    return _Welded(points, weld, triangles[keep], corners[keep])


def _simplified(
    mesh: MeshData, welded: _Welded, target: int, name: str, keep_borders: bool = False
) -> tuple[MeshData, float] | None:
    """One level of about `target` triangles and its error; None if the library's output has
    non-finite positions. `keep_borders`: no open border's vertex collapses (the joint regions'
    seams)."""
    with _LIBRARY_LOCK:
        points, faces, collapses = fast_simplification.simplify(
            welded.positions, welded.triangles.astype(np.int32), target_count=target, return_collapses=True,
            preserve_border=keep_borders,
        )  # fmt: skip
    points = np.asarray(points, dtype=np.float64)
    if not np.isfinite(points).all():
        return None
    # Each collapse (i0, i1) merges welded vertex i1 into i0; follow the chains to the survivors.
    root = np.arange(len(welded.positions))
    collapses = np.asarray(collapses, dtype=np.int64).reshape(-1, 2)
    root[collapses[:, 1]] = collapses[:, 0]
    while True:
        jumped = root[root]
        if np.array_equal(jumped, root):
            break
        root = jumped
    # The library keeps the triangles not collapsed away in order and numbers the survivors in
    # order, so its output is this mapping; checked, since the corners' attributes rely on it.
    mapped = root[welded.triangles]
    kept = (mapped[:, 0] != mapped[:, 1]) & (mapped[:, 1] != mapped[:, 2]) & (mapped[:, 2] != mapped[:, 0])
    used = np.zeros(len(root), dtype=bool)
    used[mapped[kept]] = True
    rank = np.cumsum(used) - 1
    if used.sum() != len(points) or not np.array_equal(rank[mapped[kept]], np.asarray(faces).reshape(-1, 3)):
        raise RuntimeError("fast-simplification's output does not follow its collapse record (a changed version?)")
    # Each corner takes the survivor's split copy closest in UV and normal to its own original copy.
    corners = welded.corners[kept]
    chosen = _closest_copies(mesh, welded.weld, corners, mapped[kept])
    vertices, indices = np.unique(chosen.reshape(-1), return_inverse=True)
    positions = points[rank[welded.weld[vertices]]]
    normals = _facing_normals(positions, indices.reshape(-1, 3), mesh.normals[vertices].astype(np.float64))
    skin = None if mesh.skin is None else mesh.skin.vertices(vertices)
    morph = None if mesh.morph is None else mesh.morph.vertices(vertices)
    indices = indices.astype(np.uint32)
    lod = MeshData.from_arrays(positions, normals, indices, name, mesh.uvs[vertices], skin=skin, morph=morph)
    error = level_error(welded.positions, welded.triangles, root, rank, used, points, rank[mapped[kept]])
    return lod, max(error, deform_error(mesh, welded.weld, welded.positions, root))


def _closest_copies(mesh: MeshData, weld: np.ndarray, corners: np.ndarray, survivors: np.ndarray) -> np.ndarray:
    """For each corner (render vertex `corners`, now at welded vertex `survivors`), the render
    vertex of that welded vertex whose UV and normal are nearest the corner's own: the corner's
    own vertex when it survived (nothing is nearer), else the best of the survivor's first
    `_COPIES_SEARCHED` copies (a corner by each copy of a many-copied vertex made this quadratic:
    a 100k-triangle fan whose centre had a copy per triangle)."""
    order = np.argsort(weld, kind="stable")
    counts = np.bincount(weld)
    starts = np.cumsum(counts) - counts
    flat, home = corners.reshape(-1), survivors.reshape(-1)
    uv, normal = mesh.uvs.astype(np.float64), mesh.normals.astype(np.float64)
    best = np.where(weld[flat] == home, flat, order[starts[home]])
    # the moved corners by their survivor's copies, most first: the m-th copy exists for a prefix
    # of them (a sphere's pole has hundreds of copies but few corners)
    many = np.where(weld[flat] == home, 0, np.minimum(counts[home], _COPIES_SEARCHED))
    by_count = np.argsort(-many, kind="stable")
    descending = many[by_count]
    best_cost = np.full(flat.shape, np.inf)
    for m in range(int(descending[0]) if descending.size else 0):
        rows = by_count[: int(np.searchsorted(-descending, -m, side="left"))]
        cand = order[starts[home[rows]] + m]
        here = flat[rows]
        cost = ((uv[cand] - uv[here]) ** 2).sum(1) + ((normal[cand] - normal[here]) ** 2).sum(1)
        better = cost < best_cost[rows]
        best[rows[better]] = cand[better]
        best_cost[rows[better]] = cost[better]
    return best.reshape(corners.shape)


def _facing_normals(positions: np.ndarray, triangles: np.ndarray, carried: np.ndarray) -> np.ndarray:
    """The carried normals, except where one points more than 90° from its vertex's area-weighted
    face normal (a fold the coarse surface no longer has): there that face normal."""
    face = np.cross(
        positions[triangles[:, 1]] - positions[triangles[:, 0]], positions[triangles[:, 2]] - positions[triangles[:, 0]]
    )
    summed = np.zeros_like(carried)
    for k in range(3):
        np.add.at(summed, triangles[:, k], face)
    length = np.linalg.norm(summed, axis=1)
    flip = ((summed * carried).sum(1) < 0.0) & (length > 0.0)
    out = carried.copy()
    out[flip] = summed[flip] / length[flip, None]
    return out / np.linalg.norm(out, axis=1, keepdims=True)
