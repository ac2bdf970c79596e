"""Frustum culling of bounding spheres, vectorised over a chunk of rows.

Planes are extracted from the camera-relative clip matrix (projection @ view) and normalised,
pointing inwards: a sphere is visible unless it lies entirely outside one plane. With an
infinite far plane the far row is all zero and is dropped (nothing is beyond infinity).
"""

from __future__ import annotations

import numpy as np


def frustum_planes(projection: np.ndarray, view: np.ndarray) -> np.ndarray:
    """(k, 4) float64 planes (a, b, c, d), k = 6 or 5: a*x + b*y + c*z + d >= 0 inside.

    Vulkan clip space: -w <= x, y <= w and 0 <= z <= w; reverse-Z puts the near plane at
    z = w and the far plane at z = 0."""
    m = projection.astype(np.float64) @ view.astype(np.float64)
    rows = np.stack([m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[3] - m[2], m[2]])
    norms = np.sqrt((rows[:, :3] ** 2).sum(axis=1))
    keep = norms > 1e-12
    return rows[keep] / norms[keep, None]


def frustum_planes_many(clip: np.ndarray) -> np.ndarray:
    """(C, 6, 4) planes of C clip matrices (projection @ view, (C, 4, 4)) at once, all six kept:
    for views with a finite far plane (shadow cascades), where a frame has several."""
    m = np.asarray(clip, np.float64)
    rows = np.stack(
        [m[:, 3] + m[:, 0], m[:, 3] - m[:, 0], m[:, 3] + m[:, 1], m[:, 3] - m[:, 1], m[:, 3] - m[:, 2], m[:, 2]],
        axis=1,
    )
    norms = np.sqrt((rows[..., :3] ** 2).sum(axis=-1))
    if not (norms > 1e-12).all():
        raise ValueError("frustum_planes_many needs finite far planes (use frustum_planes)")
    return rows / norms[..., None]


def spheres_visible(centers: np.ndarray, radii: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """Boolean mask of spheres at least partly inside every plane."""
    dist = centers @ planes[:, :3].T + planes[:, 3]  # (n, k) signed distances
    return (dist >= -radii[:, None]).all(axis=1)


def bounding_spheres(
    model: np.ndarray, mesh_center: np.ndarray, mesh_radius: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World (camera-relative) spheres of mesh instances: centre transformed by the model matrix,
    radius scaled by the largest column length of its 3x3 part (covers any non-uniform scale)."""
    m3 = model[:, :3, :3].astype(np.float64)
    centers = np.einsum("nij,nj->ni", m3, mesh_center) + model[:, :3, 3]
    scale = np.sqrt((m3 * m3).sum(axis=1).max(axis=1))
    return centers, mesh_radius * scale
