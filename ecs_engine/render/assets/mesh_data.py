"""Mesh data the renderer uploads once and many entities share: positions, normals, texture
coordinates and tangents, checked and frozen; bounding spheres; tangent generation; resizing.

Loading files is in mesh_loading.py, the shapes (cube, sphere, ...) in primitives.py.

Texture coordinates follow glTF and Vulkan: (0, 0) is the image's top-left corner. Tangents are
(x, y, z, w), as glTF defines them: a unit vector along +u in the surface, and w = +1 or -1, the
handedness, so that the bitangent w * cross(normal, tangent) points up the image (towards -v),
where a normal map's green channel points (MikkTSpace in OpenGL's v-up coordinates)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .morph_targets import MorphTargets
from .skin_weights import SkinWeights

__all__ = ["MeshData", "bounding_sphere", "normalized", "tangent_frames"]


def _frozen(values: object, dtype: type, name: str) -> np.ndarray:
    """A C-contiguous, read-only array of `dtype`; arrays we froze earlier are shared, not copied."""
    if (
        isinstance(values, np.ndarray)
        and values.dtype == dtype
        and values.flags.c_contiguous
        and not values.flags.writeable
        and values.base is None
    ):
        return values
    try:
        array: np.ndarray = np.array(values, dtype=dtype, order="C", copy=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"MeshData.{name}: {exc}") from None
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class MeshData:
    """One triangle mesh, immutable because many entities share it and the GPU copy is made once.

    `center`/`radius` are a bounding sphere enclosing every vertex, for culling and camera framing.
    Build one with `MeshData.from_arrays`, which computes the sphere (and the tangents). Without
    texture coordinates every vertex gets (0, 0) and tangents any unit vector across the normal."""

    positions: np.ndarray  # (V, 3) float32
    normals: np.ndarray  # (V, 3) float32, unit length
    indices: np.ndarray  # (I,) uint32, triangle list, counter-clockwise seen from outside
    name: str
    center: np.ndarray  # (3,) float32
    radius: float
    uvs: np.ndarray = None  # type: ignore[assignment]  # (V, 2) float32; None: zeros
    tangents: np.ndarray = None  # type: ignore[assignment]  # (V, 4) float32; None: made by tangent_frames
    # How to make this mesh again, as JSON (saved scenes refer to the mesh by it instead of copying
    # its arrays; render/assets/scene_assets.py): {"primitive": name, "args": {...}}, {"file": path} or
    # {"file": path, "part": k} (a model's part), {"normalized": size, "of": source} or
    # {"normalized_together": size, "of": [sources], "part": k}; None: unknown. Read-only.
    source: dict[str, Any] | None = None
    skin: SkinWeights | None = None  # the joints and weights that move each vertex; None: not skinned
    morph: MorphTargets | None = None  # its morph targets; None: none

    def __post_init__(self) -> None:
        for field, dtype in (
            ("positions", np.float32),
            ("normals", np.float32),
            ("indices", np.uint32),
            ("center", np.float32),
        ):
            object.__setattr__(self, field, _frozen(getattr(self, field), dtype, field))
        object.__setattr__(self, "radius", float(self.radius))
        v = self.positions.shape[0] if self.positions.ndim == 2 else -1
        if self.positions.shape != (v, 3) or self.normals.shape != (v, 3):
            raise ValueError(
                f"MeshData {self.name!r}: positions and normals must both be (V, 3), got "
                f"{self.positions.shape} and {self.normals.shape}"
            )
        if self.uvs is None:
            object.__setattr__(self, "uvs", np.zeros((v, 2), np.float32))
        object.__setattr__(self, "uvs", _frozen(self.uvs, np.float32, "uvs"))
        if self.uvs.shape != (v, 2) or not np.isfinite(self.uvs).all():
            raise ValueError(f"MeshData {self.name!r}: uvs must be finite and (V, 2), got shape {self.uvs.shape}")
        if self.indices.ndim != 1 or self.indices.size % 3:
            raise ValueError(
                f"MeshData {self.name!r}: indices must be a flat triangle list (length a multiple "
                f"of 3), got shape {self.indices.shape}"
            )
        if self.indices.size and int(self.indices.max()) >= v:
            raise ValueError(f"MeshData {self.name!r}: index {int(self.indices.max())} out of range for {v} vertices")
        if not np.isfinite(self.positions).all():
            raise ValueError(f"MeshData {self.name!r}: positions must be finite")
        if v and not np.allclose(np.linalg.norm(self.normals, axis=1), 1.0, atol=1e-3):
            raise ValueError(f"MeshData {self.name!r}: normals must be unit length")
        if self.center.shape != (3,) or not np.isfinite(self.center).all() or not 0.0 <= self.radius < np.inf:
            raise ValueError(f"MeshData {self.name!r}: bad bounding sphere {self.center}, {self.radius}")
        if self.skin is not None and self.skin.vertex_count != v:
            raise ValueError(f"MeshData {self.name!r}: skin weights for {self.skin.vertex_count} vertices, not {v}")
        if self.morph is not None and self.morph.vertex_count != v:
            raise ValueError(f"MeshData {self.name!r}: morph targets for {self.morph.vertex_count} vertices, not {v}")
        if self.tangents is None:
            tangents = tangent_frames(self.positions, self.normals, self.uvs, self.indices)
            object.__setattr__(self, "tangents", tangents)
        object.__setattr__(self, "tangents", _frozen(self.tangents, np.float32, "tangents"))
        t = self.tangents
        if t.shape != (v, 4) or not np.isfinite(t).all():
            raise ValueError(f"MeshData {self.name!r}: tangents must be finite and (V, 4), got shape {t.shape}")
        if v and not (
            np.allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-3) and np.isin(t[:, 3], (-1.0, 1.0)).all()
        ):
            raise ValueError(f"MeshData {self.name!r}: tangents must be unit xyz with w = +1 or -1")

    @classmethod
    def from_arrays(
        cls,
        positions: np.ndarray,
        normals: np.ndarray,
        indices: np.ndarray,
        name: str,
        uvs: np.ndarray | None = None,
        tangents: np.ndarray | None = None,
        source: dict[str, Any] | None = None,
        skin: SkinWeights | None = None,
        morph: MorphTargets | None = None,
    ) -> MeshData:
        """Validate and freeze the arrays and compute the bounding sphere (and, when not given,
        the tangents from the texture coordinates)."""
        positions = _frozen(positions, np.float32, "positions")
        center, radius = bounding_sphere(positions)
        if morph is not None:  # the farthest its targets move a vertex at weights within [-1, 1]
            radius += float(np.linalg.norm(morph.positions.astype(np.float64), axis=2).sum(axis=0).max(initial=0.0))
        indices = np.asarray(indices).reshape(-1)
        return cls(positions, normals, indices, name, center, radius, uvs, tangents, source, skin, morph)  # type: ignore[arg-type]

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def triangle_count(self) -> int:
        return int(self.indices.size // 3)


def bounding_sphere(points: np.ndarray) -> tuple[np.ndarray, float]:
    """A tight, cheap sphere around `points` (N, 3): the smallest of Ritter's sphere and the spheres about
    the box centre and the vertex mean (the last wins on symmetric shapes like the torus knot). The radius
    is measured from the float32 centre and padded by 1e-6 so float32 checks hold."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if p.shape[0] == 0:
        return np.zeros(3, np.float32), 0.0
    # Ritter: start from an approximate diameter, then grow towards the farthest outlier a few times.
    b = p[np.argmax(((p - p[0]) ** 2).sum(1))]
    c = p[np.argmax(((p - b) ** 2).sum(1))]
    center, radius = (b + c) / 2, float(np.linalg.norm(b - c)) / 2
    for _ in range(32):
        d = np.sqrt(((p - center) ** 2).sum(1))
        far = int(np.argmax(d))
        if d[far] <= radius:
            break
        grown = (radius + d[far]) / 2
        center = center + (d[far] - grown) / d[far] * (p[far] - center)
        radius = grown
    candidates = [x.astype(np.float32) for x in (center, (p.min(0) + p.max(0)) / 2, p.mean(0))]
    radii = [float(np.sqrt(((p - cand.astype(np.float64)) ** 2).sum(1).max())) for cand in candidates]
    best = int(np.argmin(radii))
    return candidates[best], radii[best] * (1 + 1e-6)


def normalized(mesh: MeshData, size: float = 1.0) -> MeshData:
    """A copy centred on its bounding-box centre, uniformly scaled so its largest extent is `size`,
    so demos can show any model at a known size."""
    return normalized_together([mesh], size)[0]


def normalized_together(meshes: list[MeshData], size: float = 1.0) -> list[MeshData]:
    """The parts of one model, moved and scaled as one (`normalized` of their union)."""
    if not 0.0 < size < np.inf:
        raise ValueError(f"size must be a finite number above 0, got {size}")
    if not meshes:
        return []
    lo = np.min([m.positions.astype(np.float64).min(0) for m in meshes], axis=0)
    hi = np.max([m.positions.astype(np.float64).max(0) for m in meshes], axis=0)
    extent = float((hi - lo).max())
    scale = size / extent if extent > 0 else 1.0
    # the sources and the size make them again (saved scenes): of one mesh, or of every part
    sources: list[dict[str, Any] | None] = [None] * len(meshes)
    if len(meshes) == 1 and meshes[0].source:
        sources = [{"normalized": float(size), "of": meshes[0].source}]
    elif all(m.source for m in meshes):
        together = [m.source for m in meshes]
        sources = [{"normalized_together": float(size), "of": together, "part": i} for i in range(len(meshes))]
    return [
        MeshData.from_arrays(
            (m.positions.astype(np.float64) - (lo + hi) / 2) * scale,
            m.normals,
            m.indices,
            m.name,
            m.uvs,
            m.tangents,
            source,
        )
        for m, source in zip(meshes, sources)
    ]


def tangent_frames(positions: np.ndarray, normals: np.ndarray, uvs: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Per-vertex tangents (V, 4) from the texture coordinates (Lengyel's method): each triangle's
    directions of +u and +v in space, summed over the triangles at a vertex, made perpendicular to
    its normal; w is the handedness (see the module's note). Where the coordinates give no direction (no UVs, degenerate
    ones) the tangent is any unit vector across the normal, with w = 1."""
    p = np.asarray(positions, np.float64)
    n = np.asarray(normals, np.float64)
    uv = np.asarray(uvs, np.float64)
    tris = np.asarray(indices, np.int64).reshape(-1, 3)
    count = len(p)
    t_sum = np.zeros((count, 3))
    b_sum = np.zeros((count, 3))
    if len(tris):
        e1, e2 = p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]]
        d1, d2 = uv[tris[:, 1]] - uv[tris[:, 0]], uv[tris[:, 2]] - uv[tris[:, 0]]
        r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
        ok = np.abs(r) > 1e-20
        inv = np.where(ok, 1.0 / np.where(ok, r, 1.0), 0.0)[:, None]
        t_face = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * inv
        b_face = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * inv
        flat = tris.reshape(-1)
        for k in range(3):
            t_sum[:, k] = np.bincount(flat, weights=np.repeat(t_face[:, k], 3), minlength=count)
            b_sum[:, k] = np.bincount(flat, weights=np.repeat(b_face[:, k], 3), minlength=count)
    t = t_sum - n * (n * t_sum).sum(1, keepdims=True)
    length = np.linalg.norm(t, axis=1, keepdims=True)
    # any perpendicular: the axis least along the normal, crossed with it
    axis = np.eye(3)[np.argmin(np.abs(n), axis=1)]
    other = np.cross(n, axis)
    other /= np.maximum(np.linalg.norm(other, axis=1, keepdims=True), 1e-300)
    good = (length > 1e-12 * np.maximum(np.linalg.norm(t_sum, axis=1, keepdims=True), 1e-300)) & (length > 0)
    t = np.where(good, t / np.where(good, length, 1.0), other)
    w = np.where((np.cross(n, t) * b_sum).sum(1) > 0.0, -1.0, 1.0)  # w * cross(n, t) points up the image
    out = np.empty((count, 4), np.float32)
    out[:, :3] = t
    out[:, 3] = w
    return out
