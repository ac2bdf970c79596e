"""Affine matrices to and from position, rotation and scale, in float64 (the gizmo, reparenting
that keeps an entity where it is)."""

from __future__ import annotations

import math

import numpy as np

from .transform import quat_to_mat3


def trs_matrices(position: np.ndarray, rotation: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(n, 4, 4) float64 matrices [row, column] of rows of position (n, 3), unit quaternion
    (n, 4) and scale (n, 3): translate * rotate * scale."""
    n = len(position)
    out = np.zeros((n, 4, 4))
    out[:, :3, :3] = quat_to_mat3(np.asarray(rotation, np.float64)) * np.asarray(scale, np.float64)[:, None, :]
    out[:, :3, 3] = position
    out[:, 3, 3] = 1.0
    return out


def decompose(m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, unit quaternion (x, y, z, w) and scale of an affine matrix without shear."""
    linear = m[:3, :3]
    scale = np.linalg.norm(linear, axis=0)
    if np.linalg.det(linear) < 0:
        scale[0] = -scale[0]
    r = linear / np.where(scale == 0.0, 1.0, scale)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = math.sqrt(trace + 1.0) * 2
        q = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2]) * 2
        q = [0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s]
    elif r[1, 1] > r[2, 2]:
        s = math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2]) * 2
        q = [(r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s]
    else:
        s = math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1]) * 2
        q = [(r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s]
    quat = np.array(q)
    return m[:3, 3].copy(), quat / np.linalg.norm(quat), scale
