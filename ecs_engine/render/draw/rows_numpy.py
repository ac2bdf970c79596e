"""The NumPy reference of instance_rows.py's kernels (what they give without numba, and what
tests hold them to): cull, key, sort and write a chunk's rows."""

from __future__ import annotations

import numpy as np

from ...maths.culling import bounding_spheres, spheres_visible

# a chunk whose rows neither skin nor morph: misc.z and misc.w carry nothing per row
NO_EXTRA = np.zeros(0, dtype=np.uint64)


def _determinant3(m3: np.ndarray) -> np.ndarray:
    return (
        m3[:, 0, 0] * (m3[:, 1, 1] * m3[:, 2, 2] - m3[:, 1, 2] * m3[:, 2, 1])
        - m3[:, 0, 1] * (m3[:, 1, 0] * m3[:, 2, 2] - m3[:, 1, 2] * m3[:, 2, 0])
        + m3[:, 0, 2] * (m3[:, 1, 0] * m3[:, 2, 1] - m3[:, 1, 1] * m3[:, 2, 0])
    )


def write_rows_numpy(
    model: np.ndarray,
    handle: np.ndarray,
    material: np.ndarray,
    centers: np.ndarray,
    radii: np.ndarray,
    planes: np.ndarray,
    n_materials: int,
    rows: np.ndarray,
    key_counts: np.ndarray,
    extra: np.ndarray = NO_EXTRA,
) -> int:
    """Reference version of `write_rows`."""
    keys = handle.astype(np.int64) * 2 + (_determinant3(model[:, :3, :3]) < 0)
    if len(planes):
        c, r = bounding_spheres(model, centers[handle], radii[handle])
        keys = np.where(spheres_visible(c, r, planes), keys, -1)
    key_counts[:] = np.bincount(keys[keys >= 0], minlength=len(key_counts))[: len(key_counts)]
    return _write_keyed_numpy(model, material, keys, n_materials, rows, extra)


def _write_keyed_numpy(
    model: np.ndarray, material: np.ndarray, keys: np.ndarray, n_materials: int, rows: np.ndarray, extra: np.ndarray
) -> int:
    """The rows whose key is not -1 into `rows`, sorted by key (stable): write_rows' order."""
    visible = np.flatnonzero(keys >= 0)
    order = visible[np.argsort(keys[visible], kind="stable")]
    n = len(order)
    out = rows[:n]
    out["model"] = model[order, :3, :]
    out["misc"][:, 0] = material[order] % n_materials
    out["misc"][:, 1] = keys[order]
    out["misc"][:, 2:] = extra[order].view(np.uint32).reshape(-1, 2) if len(extra) else 0
    return n
