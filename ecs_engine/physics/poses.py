"""The bodies' poses and velocities moved from the library's shared buffers into component
columns: one pass per table, compiled with numba (the GIL released); NumPy otherwise."""

from __future__ import annotations

import numpy as np

from .. import native


def _poses_kernel(positions, rotations, rows, into, out_position, out_rotation):  # pragma: no cover
    for i in range(len(rows)):
        r, d = rows[i], into[i]
        out_position[d, 0] = positions[r, 0]
        out_position[d, 1] = positions[r, 1]
        out_position[d, 2] = positions[r, 2]
        x, y = np.float64(rotations[r, 0]), np.float64(rotations[r, 1])
        z, w = np.float64(rotations[r, 2]), np.float64(rotations[r, 3])
        inv = 1.0 / np.sqrt(x * x + y * y + z * z + w * w)  # float32's unit length is not float64's
        out_rotation[d, 0] = x * inv
        out_rotation[d, 1] = y * inv
        out_rotation[d, 2] = z * inv
        out_rotation[d, 3] = w * inv


def _vectors_kernel(vectors, rows, into, out):  # pragma: no cover
    for i in range(len(rows)):
        r, d = rows[i], into[i]
        out[d, 0] = vectors[r, 0]
        out[d, 1] = vectors[r, 1]
        out[d, 2] = vectors[r, 2]


pose_rows = native.inner(_poses_kernel)
_vectors = native.njit(_vectors_kernel)


def copy_poses(
    positions: np.ndarray,
    rotations: np.ndarray,
    rows: np.ndarray,
    into: np.ndarray,
    out_position: np.ndarray,
    out_rotation: np.ndarray,
) -> None:
    """out_position[into] = positions[rows, :3]; out_rotation[into] = rotations[rows] made unit
    in float64 (`positions`: (M, 4) float64, `rotations`: (M, 4) float32, the library's buffers)."""
    if native.AVAILABLE and out_position.flags.c_contiguous and out_rotation.flags.c_contiguous:
        pose_rows(positions, rotations, rows, into, out_position, out_rotation)
        return
    rot = rotations[rows].astype(np.float64)
    out_position[into] = positions[rows, :3]
    out_rotation[into] = rot / np.sqrt(np.einsum("ij,ij->i", rot, rot))[:, None]


def copy_vectors(vectors: np.ndarray, rows: np.ndarray, into: np.ndarray, out: np.ndarray) -> None:
    """out[into] = vectors[rows, :3] (`vectors`: (M, 4) float32, a buffer of the library's)."""
    if _vectors is not None and out.flags.c_contiguous:
        _vectors(vectors, rows, into, out)
    else:
        out[into] = vectors[rows, :3]
