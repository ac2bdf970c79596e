"""The error of a level of detail (mesh_lod.py): how far the simplified surface strays from the
original, an upper bound sampled at vertices, in the mesh's units.

It is the largest of each simplified vertex's distance to the original triangles around the
vertices collapsed into it, and each original vertex's distance to the simplified triangles around
its and its neighbours' survivors. Each is a distance to some of the surface's triangles, so at
least the distance to the whole surface: the bound errs on the coarse level's side (it is switched
to later), never on the screen's. A Hausdorff distance measured at the vertices; a vertex the
optimum moved beyond its own collapsed region makes it loose (up to about 3x seen on a subdivided
knot, 1.3x on the torus knot).

Why not the library's quadric error: it is a sum of squared plane distances, not a length, and
grows with the number of collapses merged, so it cannot be projected to pixels.

Why compiled loops, in bounded memory: the first form expanded every (vertex, nearby triangle) pair
into NumPy arrays at once, about 16 KB a vertex (4.3 GB for a 263k-vertex sphere) and most of
the build's time. Here one numba kernel (GIL released) walks the pairs with a few index arrays
(CSR adjacency) beside the mesh; without numba the same pairs go through NumPy in blocks of
`_BLOCK`, so memory stays bounded either way."""

from __future__ import annotations

from typing import Final

import numpy as np

from ... import native

__all__ = ["level_error", "point_triangle_distance"]

#: Pairs (point, triangle) measured at once by the NumPy form: about 200 bytes each in temporaries.
_BLOCK: Final = 1 << 16
#: A survivor with more simplified triangles than this (a fan's centre, a UV sphere's pole) is not
#: searched from an original vertex that has a smaller survivor nearby: the triangles they share
#: are among the smaller one's, and searching every fan triangle from every rim vertex was
#: quadratic (a 5.7 MB OBJ of a 100k-triangle fan passed 10 s). Any subset of triangles still
#: bounds the distance from above.
_BIG_FAN: Final = 256
#: At most this many (lost vertex, triangle) distances: an original vertex none of whose
#: neighbours survived (a part collapsed away) is measured against every simplified triangle,
#: or against an evenly strided subset of them when that would cost more (the nearest of a subset
#: is still at least the distance to the surface, so the bound holds, only looser).
_LOST_BUDGET: Final = 1 << 24


def level_error(
    original: np.ndarray,
    triangles: np.ndarray,
    root: np.ndarray,
    rank: np.ndarray,
    used: np.ndarray,
    points: np.ndarray,
    faces: np.ndarray,
) -> float:
    """The level's error. `original` (W, 3) welded positions and `triangles` (T, 3) their usable
    triangles; `root` each welded vertex's survivor, `used` whether a survivor is in the output
    and `rank` its output index; `points` (P, 3) and `faces` (F, 3) the simplified mesh."""
    if len(faces) == 0 or len(triangles) == 0:
        return 0.0
    original = np.ascontiguousarray(original, dtype=np.float64)
    points = np.ascontiguousarray(points, dtype=np.float64)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    home = np.where(used[root], rank[root], -1).astype(np.int64)  # welded vertex -> its survivor, -1 if gone
    # simplified vertex -> the original triangles of its collapsed vertices (every corner names one)
    near = home[triangles.reshape(-1)]
    # original vertex -> its triangles, simplified vertex -> its faces (CSR)
    vt_start, vt_tri = _adjacency(triangles, len(original))
    ft_start, ft_face = _adjacency(faces, len(points))
    if _outward_kernel is not None and _inward_kernel is not None:
        outward = np.full(len(points), np.inf)
        _outward_kernel(points, original, triangles, near, outward)
        inward = np.full(len(original), np.inf)
        _inward_kernel(original, triangles, vt_start, vt_tri, home, points, faces, ft_start, ft_face, _BIG_FAN, inward)
    else:
        outward = _outward_numpy(points, original, triangles, near)
        inward = _inward_numpy(original, triangles, vt_start, vt_tri, home, points, faces, ft_start, ft_face)
    lost = np.flatnonzero(np.isinf(inward) & (np.diff(vt_start) > 0))
    if lost.size:
        stride = -(-(lost.size * len(faces)) // _LOST_BUDGET)
        inward[lost] = _nearest_of(original[lost], points, faces[::stride])
    both = np.concatenate([outward[np.isfinite(outward)], inward[np.isfinite(inward)]])
    return float(both.max()) if both.size else 0.0


def _adjacency(triangles: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Per vertex, the triangles using it: vertex v's are tri[start[v]:start[v + 1]]."""
    corners = triangles.reshape(-1)
    order = np.argsort(corners, kind="stable")
    start = np.zeros(count + 1, dtype=np.int64)
    np.cumsum(np.bincount(corners, minlength=count), out=start[1:])
    return start, order // 3


def _outward_numpy(points: np.ndarray, original: np.ndarray, triangles: np.ndarray, near: np.ndarray) -> np.ndarray:
    outward = np.full(len(points), np.inf)
    for s in range(0, len(near), _BLOCK):
        corner = np.arange(s, min(s + _BLOCK, len(near)))
        tri = triangles[corner // 3]
        keep = near[corner] >= 0
        d = point_triangle_distance(points[near[corner][keep]], *(original[tri[keep, k]] for k in range(3)))
        np.minimum.at(outward, near[corner][keep], d)
    return outward


def _inward_numpy(
    original: np.ndarray,
    triangles: np.ndarray,
    vt_start: np.ndarray,
    vt_tri: np.ndarray,
    home: np.ndarray,
    points: np.ndarray,
    faces: np.ndarray,
    ft_start: np.ndarray,
    ft_face: np.ndarray,
) -> np.ndarray:
    """The kernel's pairs in NumPy: per block of original vertices, the unique (vertex, survivor)
    pairs, then their faces in blocks of `_BLOCK` distances."""
    inward = np.full(len(original), np.inf)
    per_vertex = np.diff(vt_start)
    step = max(1, _BLOCK // 32)
    for s in range(0, len(original), step):
        v = np.arange(s, min(s + step, len(original)))
        n = per_vertex[v]
        query = np.repeat(v, n)
        tri = vt_tri[np.repeat(vt_start[v], n) + (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n))]
        homes = home[triangles[tri]]  # (pairs, 3)
        query, homes = np.repeat(query, 3), homes.reshape(-1)
        keys = np.unique((query * len(points) + homes)[homes >= 0])
        query, homes = np.divmod(keys, len(points))
        count = ft_start[homes + 1] - ft_start[homes]
        has_small = np.zeros(len(original), dtype=bool)
        has_small[query[count <= _BIG_FAN]] = True
        keep = (count <= _BIG_FAN) | ~has_small[query]
        query, homes, count = query[keep], homes[keep], count[keep]
        ends = np.cumsum(count)
        begin = 0
        while begin < len(query):  # pairs whose faces fit one block (at least one pair)
            end = max(begin + 1, int(np.searchsorted(ends, (ends[begin] - count[begin]) + _BLOCK, side="right")))
            q, h, c = query[begin:end], homes[begin:end], count[begin:end]
            pair_query = np.repeat(q, c)
            pair_face = ft_face[np.repeat(ft_start[h], c) + (np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c))]
            d = point_triangle_distance(original[pair_query], *(points[faces[pair_face, k]] for k in range(3)))
            np.minimum.at(inward, pair_query, d)
            begin = end
    return inward


def _nearest_of(queries: np.ndarray, points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each query point's distance to the nearest of `faces`."""
    if _nearest_kernel is not None:
        out = np.full(len(queries), np.inf)
        _nearest_kernel(np.ascontiguousarray(queries), points, faces, out)
        return out
    out = np.full(len(queries), np.inf)
    rows = max(1, _BLOCK // max(1, len(faces)))
    for s in range(0, len(queries), rows):
        q = queries[s : s + rows]
        many = np.repeat(q, len(faces), axis=0)
        tri = np.tile(faces, (len(q), 1))
        d = point_triangle_distance(many, *(points[tri[:, k]] for k in range(3)))
        out[s : s + rows] = d.reshape(len(q), len(faces)).min(axis=1)
    return out


def point_triangle_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance from each point to its triangle (all (N, 3)): the closest point by the triangle's
    Voronoi regions (Ericson, Real-Time Collision Detection, 5.1.5), vectorised. Worked as (3, N)
    rows: sums over 3 contiguous rows are several times faster than over (N, 3)'s short rows."""
    p, a, b, c = (np.ascontiguousarray(x.T, dtype=np.float64) for x in (p, a, b, c))
    ab, ac, ap, bp, cp = b - a, c - a, p - a, p - b, p - c
    d1, d2, d3, d4, d5, d6 = ((x * y).sum(0) for x, y in ((ab, ap), (ac, ap), (ab, bp), (ac, bp), (ab, cp), (ac, cp)))
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        closest = a + ab * (vb / denom) + ac * (vc / denom)  # inside the face
        # edges, then vertices, each overriding where its region holds (the regions do not overlap)
        t_ab, t_ac, t_bc = d1 / (d1 - d3), d2 / (d2 - d6), (d4 - d3) / ((d4 - d3) + (d5 - d6))
        regions = (
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), lambda: a + ab * t_ab),
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), lambda: a + ac * t_ac),
            ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), lambda: b + (c - b) * t_bc),
            ((d1 <= 0) & (d2 <= 0), lambda: a),
            ((d3 >= 0) & (d4 <= d3), lambda: b),
            ((d6 >= 0) & (d5 <= d6), lambda: c),
        )
        for region, point in regions:
            if region.any():
                closest = np.where(region, point(), closest)
    return np.sqrt(((p - np.nan_to_num(closest)) ** 2).sum(0))


# --------------------------------------------------------------------------- compiled forms
def _distance(queries, i, points, ia, ib, ic):  # pragma: no cover - compiled
    """The distance from queries[i] to the triangle points[ia, ib, ic]: point_triangle_distance's
    regions in the book's order, returning at the first that holds. Indices, not row views: a
    view made per call cost several times the arithmetic."""
    px, py, pz = queries[i, 0], queries[i, 1], queries[i, 2]
    ax, ay, az = points[ia, 0], points[ia, 1], points[ia, 2]
    bx, by, bz = points[ib, 0], points[ib, 1], points[ib, 2]
    cx, cy, cz = points[ic, 0], points[ic, 1], points[ic, 2]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return np.sqrt(apx * apx + apy * apy + apz * apz)
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return np.sqrt(bpx * bpx + bpy * bpy + bpz * bpz)
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        x, y, z = apx - t * abx, apy - t * aby, apz - t * abz
        return np.sqrt(x * x + y * y + z * z)
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return np.sqrt(cpx * cpx + cpy * cpy + cpz * cpz)
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        x, y, z = apx - t * acx, apy - t * acy, apz - t * acz
        return np.sqrt(x * x + y * y + z * z)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        x, y, z = bpx - t * (cx - bx), bpy - t * (cy - by), bpz - t * (cz - bz)
        return np.sqrt(x * x + y * y + z * z)
    denom = va + vb + vc
    if denom == 0.0:  # no area and no region above held: its corners bound the distance
        return min(
            np.sqrt(apx * apx + apy * apy + apz * apz),
            np.sqrt(bpx * bpx + bpy * bpy + bpz * bpz),
            np.sqrt(cpx * cpx + cpy * cpy + cpz * cpz),
        )
    v, w = vb / denom, vc / denom
    x, y, z = apx - abx * v - acx * w, apy - aby * v - acy * w, apz - abz * v - acz * w
    return np.sqrt(x * x + y * y + z * z)


_distance_compiled = native.inner(_distance)


def _outward(points, original, triangles, near, out):  # pragma: no cover - compiled
    for corner in range(near.shape[0]):
        s = near[corner]
        if s < 0:
            continue
        t = corner // 3
        d = _distance_compiled(points, s, original, triangles[t, 0], triangles[t, 1], triangles[t, 2])
        if d < out[s]:
            out[s] = d


def _inward(
    original, triangles, vt_start, vt_tri, home, points, faces, ft_start, ft_face, big_fan, out
):  # pragma: no cover
    seen = np.full(points.shape[0], -1, np.int64)  # the last vertex that measured this survivor's faces
    for v in range(original.shape[0]):
        best = np.inf
        small = False  # has v a survivor near it with at most big_fan triangles?
        for j in range(vt_start[v], vt_start[v + 1]):
            for k in range(3):
                h = home[triangles[vt_tri[j], k]]
                if h >= 0 and ft_start[h + 1] - ft_start[h] <= big_fan:
                    small = True
        for j in range(vt_start[v], vt_start[v + 1]):
            t = vt_tri[j]
            for k in range(3):
                h = home[triangles[t, k]]
                if h < 0 or seen[h] == v or (small and ft_start[h + 1] - ft_start[h] > big_fan):
                    continue
                seen[h] = v
                for m in range(ft_start[h], ft_start[h + 1]):
                    f = ft_face[m]
                    d = _distance_compiled(original, v, points, faces[f, 0], faces[f, 1], faces[f, 2])
                    if d < best:
                        best = d
        out[v] = best


def _nearest(queries, points, faces, out):  # pragma: no cover - compiled
    for i in range(queries.shape[0]):
        best = np.inf
        for j in range(faces.shape[0]):
            d = _distance_compiled(queries, i, points, faces[j, 0], faces[j, 1], faces[j, 2])
            if d < best:
                best = d
        out[i] = best


_outward_kernel = native.njit(_outward)
_inward_kernel = native.njit(_inward)
_nearest_kernel = native.njit(_nearest)
