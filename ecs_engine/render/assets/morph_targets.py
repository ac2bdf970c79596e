"""A mesh's morph targets (glTF's primitive.targets, "blend shapes"): per target, per vertex, how
far its position, normal and tangent move at weight 1. A vertex is drawn at its position plus the
sum of each target's weight times its delta (normals and tangents alike, then normalised); a
skin then moves the morphed vertex. A MeshData carries them as its `morph`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_MORPH_TARGETS = 8  # targets a mesh may have (MorphWeights holds as many weights)


@dataclass(frozen=True, eq=False)
class MorphTargets:
    positions: np.ndarray  # (T, V, 3) float32
    normals: np.ndarray  # (T, V, 3) float32 (zeros where the file gives none)
    tangents: np.ndarray  # (T, V, 3) float32 (zeros where the file gives none)
    weights: np.ndarray  # (T,) float32: the mesh's default weights (glTF mesh.weights; zeros)

    @classmethod
    def of(
        cls,
        positions: np.ndarray,
        normals: np.ndarray | None = None,
        tangents: np.ndarray | None = None,
        weights: np.ndarray | None = None,
        name: str = "mesh",
    ) -> MorphTargets:
        """Validated copies: ValueError naming `name` for more than MAX_MORPH_TARGETS targets,
        shapes that disagree or values that are not finite."""
        p = np.asarray(positions, np.float32)
        if p.ndim != 3 or p.shape[2] != 3 or not 0 < p.shape[0] <= MAX_MORPH_TARGETS:
            raise ValueError(
                f"{name}: morph targets must be (T, V, 3) with 1 to {MAX_MORPH_TARGETS} targets, got {p.shape}"
            )
        out = []
        for label, given in (("positions", p), ("normals", normals), ("tangents", tangents)):
            a = np.zeros_like(p) if given is None else np.asarray(given, np.float32)
            if a.shape != p.shape:
                raise ValueError(f"{name}: morph target {label} are {a.shape}, not {p.shape}")
            if not np.isfinite(a).all():
                raise ValueError(f"{name}: morph target {label} are not all finite")
            a.flags.writeable = False
            out.append(a)
        w = np.zeros(len(p), np.float32) if weights is None else np.asarray(weights, np.float32).reshape(-1)
        if w.shape != (len(p),) or not np.isfinite(w).all():
            raise ValueError(f"{name}: {len(p)} morph targets need {len(p)} finite default weights, got {w.tolist()}")
        w.flags.writeable = False
        return cls(out[0], out[1], out[2], w)

    @property
    def count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[1])

    def vertices(self, rows: np.ndarray) -> MorphTargets:
        """The deltas of vertices `rows`, in that order (a level of detail's, a cut mesh's)."""
        return MorphTargets(self.positions[:, rows], self.normals[:, rows], self.tangents[:, rows], self.weights)

    def applied(self, weights: np.ndarray, positions: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(positions, normals) of the mesh morphed by `weights` (T,): the CPU's reference."""
        w = np.asarray(weights, np.float64)[: self.count]
        p = positions + np.einsum("t,tvc->vc", w, self.positions.astype(np.float64))
        n = normals + np.einsum("t,tvc->vc", w, self.normals.astype(np.float64))
        length = np.linalg.norm(n, axis=1, keepdims=True)
        return p, np.where(length > 0, n / np.maximum(length, 1e-30), normals)
