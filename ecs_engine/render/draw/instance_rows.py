"""A render chunk's CPU work: cull its rows, sort the visible ones by (mesh, winding), and write
them as instance rows into its slice of the mapped buffer.

Two implementations give the same rows in the same order: a numba nogil kernel (one pass to
cull and count, one to write; a counting sort over the few (mesh, winding) keys) and the NumPy
reference. Measured on the GPU host, the NumPy version on 4,096-row chunks cost ~0.58 us per
entity and did not scale with threads (many small calls, each holding the GIL).

Row layout (layouts.INSTANCE, 64 bytes = 16 words): model rows 0-2 (12 floats), material index,
key (mesh * 2 + mirrored: the indirect mode's compute shader reads it) and 2 zero words. The
vertex shader derives the normal matrix from the model matrix (its cofactor), so rows carry no
normal matrix: at a million entities the jobs write 45 MB a frame instead of 79 MB, and a
per-entity draw pushes 64 bytes instead of 112.
"""

from __future__ import annotations

import numpy as np

from ... import native
from ...maths.culling import bounding_spheres, spheres_visible
from ..layouts import INSTANCE
from .rows_numpy import NO_EXTRA, _determinant3, _write_keyed_numpy, write_rows_numpy

INSTANCE_DTYPE = INSTANCE.dtype
# the kernel writes a row as 8 uint64 words: model rows in words 0-5, misc.xy in word 6, zw in 7
if not (INSTANCE.size == 64 and INSTANCE.offset("model") == 0 and INSTANCE.offset("misc") == 48):
    raise RuntimeError(f"the row-writing kernel assumes 64-byte rows, misc at byte 48:\n{INSTANCE.glsl()}")
NO_PLANES = np.zeros((0, 4), dtype=np.float64)


def _cull_run_kernel(model, e0, e1, e2, radius, planes, key0, keys):  # pragma: no cover - compiled
    # One run of rows of the same mesh, so the mesh's sphere is four scalars: with a per-row
    # lookup of the mesh's centre and radius (a gather) LLVM does not vectorise the loop, and
    # this loop is the row-writing's largest cost. `planes` is always 6 (a, b, c, d) (padded);
    # `model` is the run's flat float32 rows (16 a row). Writes key0 + mirrored, or -1 when the
    # sphere is wholly outside a plane; returns (plain, mirrored) counts of the visible rows.
    a0, b0, c0, d0 = planes[0], planes[1], planes[2], planes[3]
    a1, b1, c1, d1 = planes[4], planes[5], planes[6], planes[7]
    a2, b2, c2, d2 = planes[8], planes[9], planes[10], planes[11]
    a3, b3, c3, d3 = planes[12], planes[13], planes[14], planes[15]
    a4, b4, c4, d4 = planes[16], planes[17], planes[18], planes[19]
    a5, b5, c5, d5 = planes[20], planes[21], planes[22], planes[23]
    rr = radius * radius
    plain = 0
    mirrored = 0
    for i in range(keys.shape[0]):
        o = 16 * i
        m00, m01, m02, m03 = model[o], model[o + 1], model[o + 2], model[o + 3]
        m10, m11, m12, m13 = model[o + 4], model[o + 5], model[o + 6], model[o + 7]
        m20, m21, m22, m23 = model[o + 8], model[o + 9], model[o + 10], model[o + 11]
        cx = m00 * e0 + m01 * e1 + m02 * e2 + m03
        cy = m10 * e0 + m11 * e1 + m12 * e2 + m13
        cz = m20 * e0 + m21 * e1 + m22 * e2 + m23
        sx = m00 * m00 + m10 * m10 + m20 * m20
        sy = m01 * m01 + m11 * m11 + m21 * m21
        sz = m02 * m02 + m12 * m12 + m22 * m22
        r2 = rr * max(sx, max(sy, sz))  # (scaled radius)^2: compare squares, no square root
        worst = a0 * cx + b0 * cy + c0 * cz + d0
        worst = min(worst, a1 * cx + b1 * cy + c1 * cz + d1)
        worst = min(worst, a2 * cx + b2 * cy + c2 * cz + d2)
        worst = min(worst, a3 * cx + b3 * cy + c3 * cz + d3)
        worst = min(worst, a4 * cx + b4 * cy + c4 * cz + d4)
        worst = min(worst, a5 * cx + b5 * cy + c5 * cz + d5)
        det = m00 * (m11 * m22 - m12 * m21) - m01 * (m10 * m22 - m12 * m20) + m02 * (m10 * m21 - m11 * m20)
        flip = 1 if det < 0.0 else 0
        outside = worst < 0.0 and worst * worst > r2  # worst < -radius
        keys[i] = -1 if outside else key0 + flip
        plain += 0 if outside else 1 - flip
        mirrored += 0 if outside else flip
    return plain, mirrored


def _write_rows_kernel(
    model_4x4, handle, material, centers, radii, planes, n_materials, rows, key_counts, extra
):  # pragma: no cover - compiled
    # Pass 1 culls and keys the rows, one run of equal meshes at a time (vectorised, see above),
    # and counts rows per key; pass 2 (_write_keyed) writes the visible ones by key. `planes`
    # (k <= 6, 4) are padded to six by repeating the last; none keep every row.
    n = handle.shape[0]
    floats = model_4x4.reshape(model_4x4.size)
    six = np.empty(24)
    for p in range(6):
        for c in range(4):
            six[4 * p + c] = planes[min(p, planes.shape[0] - 1), c] if planes.shape[0] > 0 else (1.0 if c == 3 else 0.0)
    keys = np.empty(n, np.int32)
    for k in range(key_counts.shape[0]):
        key_counts[k] = 0
    i = 0
    while i < n:
        h = handle[i]
        j = i + 1
        while j < n and handle[j] == h:
            j += 1
        plain, mirrored = _cull_run(
            floats[16 * i : 16 * j],
            centers[h, 0],
            centers[h, 1],
            centers[h, 2],
            radii[h],
            six,
            np.int32(2 * h),
            keys[i:j],
        )
        key_counts[2 * h] += plain
        key_counts[2 * h + 1] += mirrored
        i = j
    return _write_keyed(model_4x4, material, keys, key_counts, n_materials, np.uint64(0), rows, extra)


def _write_keyed_kernel(
    model_4x4, material, keys, key_counts, n_materials, misc_zw, rows, extra
):  # pragma: no cover - compiled
    # Pass 2: the rows whose key is not -1 written by key (a counting sort), 8 bytes at a time:
    # `rows` is a flat uint64 view (8 words a row), and so is `model` below. The current key's
    # cursor stays in a register while the key repeats (rows of one mesh come in runs). misc_zw
    # is the rows' last word (misc.z: 1 for rows no shadow falls on); `extra` (per row, or empty)
    # is ORed into it (a skinned or morphed row's misc.z and misc.w bits: Chunk.extra).
    model = model_4x4.reshape(model_4x4.size).view(np.uint64)
    offsets = np.empty(key_counts.shape[0], np.int64)
    total = 0
    for k in range(key_counts.shape[0]):
        offsets[k] = total
        total += key_counts[k]
    cursor_key = -1
    j = 0
    for i in range(keys.shape[0]):
        k = keys[i]
        if k < 0:
            continue
        if k != cursor_key:
            if cursor_key >= 0:
                offsets[cursor_key] = j
            cursor_key = k
            j = offsets[k]
        src = 8 * i
        dst = 8 * j
        for w in range(6):  # model rows 0-2: 12 floats
            rows[dst + w] = model[src + w]
        rows[dst + 6] = np.uint64(material[i] % n_materials) | (np.uint64(k) << np.uint64(32))
        rows[dst + 7] = misc_zw | extra[i] if extra.shape[0] else misc_zw
        j += 1
    return total


CULL_BLOCK = 256  # rows whose spheres are worked out, then tested against every view


def _spheres_kernel(model, e0, e1, e2, radius, cx, cy, cz, r2, flip):  # pragma: no cover - compiled
    # A block of rows of one mesh: each sphere's centre, squared radius and winding, into
    # contiguous arrays (the model rows are 16 floats apart: this loop does not vectorise, and
    # is done once for all views).
    rr = radius * radius
    for t in range(cx.shape[0]):
        o = 16 * t
        m00, m01, m02, m03 = model[o], model[o + 1], model[o + 2], model[o + 3]
        m10, m11, m12, m13 = model[o + 4], model[o + 5], model[o + 6], model[o + 7]
        m20, m21, m22, m23 = model[o + 8], model[o + 9], model[o + 10], model[o + 11]
        cx[t] = m00 * e0 + m01 * e1 + m02 * e2 + m03
        cy[t] = m10 * e0 + m11 * e1 + m12 * e2 + m13
        cz[t] = m20 * e0 + m21 * e1 + m22 * e2 + m23
        sx = m00 * m00 + m10 * m10 + m20 * m20
        sy = m01 * m01 + m11 * m11 + m21 * m21
        sz = m02 * m02 + m12 * m12 + m22 * m22
        r2[t] = rr * max(sx, max(sy, sz))
        det = m00 * (m11 * m22 - m12 * m21) - m01 * (m10 * m22 - m12 * m20) + m02 * (m10 * m21 - m11 * m20)
        flip[t] = 1 if det < 0.0 else 0


def _test_spheres_kernel(cx, cy, cz, r2, flip, planes, key0, keys):  # pragma: no cover - compiled
    # One view's six planes against a block's spheres (contiguous: vectorised); as _cull_run.
    a0, b0, c0, d0 = planes[0], planes[1], planes[2], planes[3]
    a1, b1, c1, d1 = planes[4], planes[5], planes[6], planes[7]
    a2, b2, c2, d2 = planes[8], planes[9], planes[10], planes[11]
    a3, b3, c3, d3 = planes[12], planes[13], planes[14], planes[15]
    a4, b4, c4, d4 = planes[16], planes[17], planes[18], planes[19]
    a5, b5, c5, d5 = planes[20], planes[21], planes[22], planes[23]
    plain = 0
    mirrored = 0
    for t in range(cx.shape[0]):
        x, y, z = cx[t], cy[t], cz[t]
        worst = a0 * x + b0 * y + c0 * z + d0
        worst = min(worst, a1 * x + b1 * y + c1 * z + d1)
        worst = min(worst, a2 * x + b2 * y + c2 * z + d2)
        worst = min(worst, a3 * x + b3 * y + c3 * z + d3)
        worst = min(worst, a4 * x + b4 * y + c4 * z + d4)
        worst = min(worst, a5 * x + b5 * y + c5 * z + d5)
        f = flip[t]
        outside = worst < 0.0 and worst * worst > r2[t]
        keys[t] = -1 if outside else key0 + f
        plain += 0 if outside else 1 - f
        mirrored += 0 if outside else f
    return plain, mirrored


def _cull_views_kernel(model_4x4, handle, centers, radii, planes, keys, key_counts):  # pragma: no cover - compiled
    # Several views at once (a light's shadow views): a block of rows of one mesh has its
    # spheres worked out once (_spheres), then each view's planes tested against them
    # (_test_spheres, vectorised). Measured on the GPU host, 4 views over 100k rows: 3.9 ms with
    # the planes tested in a loop per row (not vectorised). planes: (V, 24), padded as above;
    # keys[v, i] is the row's key in view v or -1; key_counts[v] the rows per key.
    n = handle.shape[0]
    views = planes.shape[0]
    floats = model_4x4.reshape(model_4x4.size)
    cx, cy, cz, r2 = np.empty(CULL_BLOCK), np.empty(CULL_BLOCK), np.empty(CULL_BLOCK), np.empty(CULL_BLOCK)
    flip = np.empty(CULL_BLOCK, np.int32)
    for v in range(views):
        for k in range(key_counts.shape[1]):
            key_counts[v, k] = 0
    i = 0
    while i < n:
        h = handle[i]
        j = i + 1
        while j < n and handle[j] == h:
            j += 1
        for b in range(i, j, CULL_BLOCK):
            m = min(CULL_BLOCK, j - b)
            _spheres(
                floats[16 * b : 16 * (b + m)], centers[h, 0], centers[h, 1], centers[h, 2], radii[h],
                cx[:m], cy[:m], cz[:m], r2[:m], flip[:m],
            )  # fmt: skip
            for v in range(views):
                plain, mirrored = _test_spheres(
                    cx[:m], cy[:m], cz[:m], r2[:m], flip[:m], planes[v], np.int32(2 * h), keys[v, b : b + m]
                )
                key_counts[v, 2 * h] += plain
                key_counts[v, 2 * h + 1] += mirrored
        i = j


def _masked_keys_kernel(model_4x4, handle, visible, keys, key_counts):  # pragma: no cover - compiled
    # Keys from a visibility decided elsewhere (temporal culling): mesh * 2 + mirrored, or -1.
    for k in range(key_counts.shape[0]):
        key_counts[k] = 0
    for i in range(handle.shape[0]):
        if not visible[i]:
            keys[i] = -1
            continue
        m = model_4x4[i]
        det = (
            m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1])
            - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
            + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0])
        )
        k = 2 * handle[i] + (1 if det < 0.0 else 0)
        keys[i] = k
        key_counts[k] += 1


_masked_keys_native = native.njit(_masked_keys_kernel)


def masked_keys(model: np.ndarray, handle: np.ndarray, visible: np.ndarray, key_counts: np.ndarray) -> np.ndarray:
    """Per row: its key (mesh * 2 + mirrored) where `visible`, else -1; counts per key into
    `key_counts`. For rows culled elsewhere (render/culling/temporal_culling.py); then `write_keyed`."""
    keys = np.empty(len(handle), np.int32)
    if _masked_keys_native is not None:
        _masked_keys_native(model, handle, visible, keys, key_counts)
        return keys
    all_keys = handle.astype(np.int64) * 2 + (_determinant3(model[:, :3, :3]) < 0)
    keys[:] = np.where(visible, all_keys, -1)
    key_counts[:] = np.bincount(keys[keys >= 0], minlength=len(key_counts))[: len(key_counts)]
    return keys


_cull_run = native.inner(_cull_run_kernel)
_spheres = native.inner(_spheres_kernel)
_test_spheres = native.inner(_test_spheres_kernel)
_write_keyed = native.inner(_write_keyed_kernel)
_write_rows_native = native.njit(_write_rows_kernel)
_write_keyed_native = native.njit(_write_keyed_kernel)
_cull_views_native = native.njit(_cull_views_kernel)


def write_rows(
    model: np.ndarray,
    handle: np.ndarray,
    material: np.ndarray,
    centers: np.ndarray,
    radii: np.ndarray,
    planes: np.ndarray | None,
    n_materials: int,
    rows: np.ndarray,
    key_counts: np.ndarray,
    extra: np.ndarray | None = None,
) -> int:
    """Cull (when `planes` is given), then write the visible rows into `rows` (INSTANCE_DTYPE,
    at least len(handle) long) sorted by key = mesh * 2 + mirrored, counting rows per key into
    `key_counts`; `extra`: per row, bits of its misc.z and misc.w (Chunk.extra). Returns the number written. Releases
    the GIL with numba."""
    extra = NO_EXTRA if extra is None else extra
    planes = NO_PLANES if planes is None else planes
    if _write_rows_native is None or not rows.flags.c_contiguous:
        return write_rows_numpy(model, handle, material, centers, radii, planes, n_materials, rows, key_counts, extra)
    if len(planes) > 6:
        raise ValueError(f"at most 6 frustum planes, got {len(planes)}")
    if not model.flags.c_contiguous:
        model = np.ascontiguousarray(model)
    return int(
        _write_rows_native(
            model,
            handle,
            material,
            centers,
            radii,
            planes,
            np.uint32(n_materials),
            rows.view(np.uint64),
            key_counts,
            extra,
        )
    )


def padded_planes(views: list[np.ndarray | None]) -> np.ndarray:
    """(V, 24) float64: each view's planes (k <= 6, 4) padded to six by repeating the last (none:
    a plane that keeps everything), for `cull_views`."""
    out = np.empty((len(views), 6, 4))
    for v, planes in enumerate(views):
        p = NO_PLANES if planes is None else np.asarray(planes, np.float64)
        if len(p) == 6:  # a frustum's: as they are (the common case, a dozen views a frame)
            out[v] = p
            continue
        if len(p) > 6:
            raise ValueError(f"at most 6 frustum planes, got {len(p)}")
        out[v] = p[np.minimum(np.arange(6), len(p) - 1)] if len(p) else (0.0, 0.0, 0.0, 1.0)
    return out.reshape(len(views), 24)


def cull_views(
    model: np.ndarray,
    handle: np.ndarray,
    centers: np.ndarray,
    radii: np.ndarray,
    planes: np.ndarray,
    keys: np.ndarray,
    key_counts: np.ndarray,
) -> None:
    """Cull a chunk against V views at once (`planes` from padded_planes): keys[v, i] = the row's
    key (mesh * 2 + mirrored) when visible in view v, else -1; key_counts[v] counts rows per key.
    Each row's sphere is worked out once, not once a view. Releases the GIL with numba."""
    if _cull_views_native is not None and model.flags.c_contiguous:
        _cull_views_native(model, handle, centers, radii, planes, keys, key_counts)
        return
    c, r = bounding_spheres(model, centers[handle], radii[handle])
    key = handle.astype(np.int64) * 2 + (_determinant3(model[:, :3, :3]) < 0)
    for v in range(len(planes)):
        visible = spheres_visible(c, r, planes[v].reshape(6, 4))
        keys[v] = np.where(visible, key, -1)
        key_counts[v] = np.bincount(key[visible], minlength=key_counts.shape[1])[: key_counts.shape[1]]


def write_keyed(
    model: np.ndarray,
    material: np.ndarray,
    keys: np.ndarray,
    key_counts: np.ndarray,
    n_materials: int,
    rows: np.ndarray,
    extra: np.ndarray | None = None,
) -> int:
    """The rows whose key (from cull_views: one view's) is not -1, written into `rows` sorted by
    key as `write_rows` writes them; returns the number written."""
    extra = NO_EXTRA if extra is None else extra
    if _write_keyed_native is not None and rows.flags.c_contiguous and model.flags.c_contiguous:
        rows64, n = rows.view(np.uint64), np.uint32(n_materials)
        return int(_write_keyed_native(model, material, keys, key_counts, n, np.uint64(0), rows64, extra))
    return _write_keyed_numpy(model, material, keys, n_materials, rows, extra)
