"""A render chunk's CPU work: cull its rows, sort the visible ones by (mesh, winding), and write
them as instance rows into its slice of the mapped buffer.

Two implementations give the same rows in the same order: a numba nogil kernel (one pass to
cull and count, one to write; a counting sort over the few (mesh, winding) keys) and the NumPy
reference. Measured on the GPU host, the NumPy version on 4,096-row chunks cost ~0.58 us per
entity and did not scale with threads (many small calls, each holding the GIL).

Row layout (INSTANCE_DTYPE, 64 bytes = 16 words): model rows 0-2 (12 floats), material index,
key (mesh * 2 + mirrored: the indirect mode's compute shader reads it) and 2 zero words. The
vertex shader derives the normal matrix from the model matrix (its cofactor), so rows carry no
normal matrix: at a million entities the jobs write 45 MB a frame instead of 79 MB, and a
per-entity draw pushes 64 bytes instead of 112.
"""

from __future__ import annotations

import numpy as np

from . import native
from .culling import bounding_spheres, spheres_visible

INSTANCE_DTYPE = np.dtype([("model", np.float32, (3, 4)), ("misc", np.uint32, 4)])
WORDS = INSTANCE_DTYPE.itemsize // 4
NO_PLANES = np.zeros((0, 4), dtype=np.float64)


def _determinant3(m3: np.ndarray) -> np.ndarray:
    return (m3[:, 0, 0] * (m3[:, 1, 1] * m3[:, 2, 2] - m3[:, 1, 2] * m3[:, 2, 1])
            - m3[:, 0, 1] * (m3[:, 1, 0] * m3[:, 2, 2] - m3[:, 1, 2] * m3[:, 2, 0])
            + m3[:, 0, 2] * (m3[:, 1, 0] * m3[:, 2, 1] - m3[:, 1, 1] * m3[:, 2, 0]))


def write_rows_numpy(model: np.ndarray, handle: np.ndarray, material: np.ndarray,
                     centers: np.ndarray, radii: np.ndarray, planes: np.ndarray, n_materials: int,
                     rows: np.ndarray, key_counts: np.ndarray) -> int:
    """Reference version of `write_rows`."""
    if len(planes):
        c, r = bounding_spheres(model, centers[handle], radii[handle])
        visible = np.flatnonzero(spheres_visible(c, r, planes))
        model, handle, material = model[visible], handle[visible], material[visible]
    n = len(handle)
    mirrored = _determinant3(model[:, :3, :3]) < 0
    key = handle.astype(np.int64) * 2 + mirrored
    order = np.argsort(key, kind="stable")
    out = rows[:n]
    out["model"] = model[order, :3, :]
    out["misc"][:, 0] = material[order] % n_materials
    out["misc"][:, 1] = key[order]
    out["misc"][:, 2:] = 0
    key_counts[:] = np.bincount(key, minlength=len(key_counts))[: len(key_counts)]
    return n


def _write_rows_kernel(model, handle, material, centers, radii, planes, n_materials, words, uwords,
                       key_counts):  # pragma: no cover - compiled
    # Pass 1 culls and keys every row, pass 2 writes the visible ones by key (a counting sort).
    # Both keep the current key's count or cursor in a register while the key repeats (rows of
    # one mesh come in runs): a counter in memory would make every row wait for the last one's
    # store. The sphere test compares squares (no square root). Together ~13% faster than the
    # plain version on 1M rows.
    n = model.shape[0]
    keys = np.empty(n, np.int32)
    for k in range(key_counts.shape[0]):
        key_counts[k] = 0
    n_planes = planes.shape[0]
    run_key = -1
    run_length = 0
    for i in range(n):
        h = handle[i]
        m = model[i]
        if n_planes > 0:
            c0, c1, c2 = centers[h, 0], centers[h, 1], centers[h, 2]
            cx = m[0, 0] * c0 + m[0, 1] * c1 + m[0, 2] * c2 + m[0, 3]
            cy = m[1, 0] * c0 + m[1, 1] * c1 + m[1, 2] * c2 + m[1, 3]
            cz = m[2, 0] * c0 + m[2, 1] * c1 + m[2, 2] * c2 + m[2, 3]
            sx = m[0, 0] * m[0, 0] + m[1, 0] * m[1, 0] + m[2, 0] * m[2, 0]
            sy = m[0, 1] * m[0, 1] + m[1, 1] * m[1, 1] + m[2, 1] * m[2, 1]
            sz = m[0, 2] * m[0, 2] + m[1, 2] * m[1, 2] + m[2, 2] * m[2, 2]
            r2 = radii[h] * radii[h] * max(sx, max(sy, sz))  # (scaled radius)^2
            worst = planes[0, 0] * cx + planes[0, 1] * cy + planes[0, 2] * cz + planes[0, 3]
            for p in range(1, n_planes):
                worst = min(worst, planes[p, 0] * cx + planes[p, 1] * cy + planes[p, 2] * cz + planes[p, 3])
            if worst < 0.0 and worst * worst > r2:  # worst < -radius: wholly outside a plane
                keys[i] = -1
                continue
        det = (m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1])
               - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
               + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]))
        k = np.int64(h) * 2 + (1 if det < 0 else 0)
        keys[i] = k
        if k == run_key:
            run_length += 1
        else:
            if run_key >= 0:
                key_counts[run_key] += run_length
            run_key = k
            run_length = 1
    if run_key >= 0:
        key_counts[run_key] += run_length
    offsets = np.empty(key_counts.shape[0], np.int64)
    total = 0
    for k in range(key_counts.shape[0]):
        offsets[k] = total
        total += key_counts[k]
    cursor_key = -1
    j = 0
    for i in range(n):
        k = keys[i]
        if k < 0:
            continue
        if k != cursor_key:
            if cursor_key >= 0:
                offsets[cursor_key] = j
            cursor_key = k
            j = offsets[k]
        m = model[i]
        for r in range(3):
            for c in range(4):
                words[j, 4 * r + c] = m[r, c]
        uwords[j, 12] = material[i] % n_materials
        uwords[j, 13] = k
        uwords[j, 14] = 0
        uwords[j, 15] = 0
        j += 1
    return total


_write_rows_native = native.njit(_write_rows_kernel)


def write_rows(model: np.ndarray, handle: np.ndarray, material: np.ndarray,
               centers: np.ndarray, radii: np.ndarray, planes: np.ndarray | None, n_materials: int,
               rows: np.ndarray, key_counts: np.ndarray) -> int:
    """Cull (when `planes` is given), then write the visible rows into `rows` (INSTANCE_DTYPE,
    at least len(handle) long) sorted by key = mesh * 2 + mirrored, counting rows per key into
    `key_counts`. Returns the number written. Releases the GIL with numba."""
    planes = NO_PLANES if planes is None else planes
    if _write_rows_native is None:
        return write_rows_numpy(model, handle, material, centers, radii, planes, n_materials, rows, key_counts)
    words = rows.view(np.float32).reshape(len(rows), WORDS)
    return int(_write_rows_native(model, handle, material, centers, radii, planes, np.uint32(n_materials),
                                  words, words.view(np.uint32), key_counts))
