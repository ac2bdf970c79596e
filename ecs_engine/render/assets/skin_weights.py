"""Which joints move each vertex of a skinned mesh, and by how much: up to eight influences per
vertex (glTF's JOINTS_0/JOINTS_1 and WEIGHTS_0/WEIGHTS_1), the weights made to sum to one as the
glTF specification asks of a renderer. Unused influences have weight 0 (their joint index is
then 0 and never read). A MeshData carries them as its `skin`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

INFLUENCES = 8  # the most joints one vertex follows


@dataclass(frozen=True, eq=False)
class SkinWeights:
    joints: np.ndarray  # (V, 8) uint16: joint indices into the skin's joint list
    weights: np.ndarray  # (V, 8) float32, each row summing to 1

    @classmethod
    def of(cls, joints: np.ndarray, weights: np.ndarray, name: str = "mesh") -> SkinWeights:
        """Validated and normalised copies of `joints` and `weights` ((V, k), k <= 8, padded to 8).
        ValueError naming `name` for a negative or non-finite weight, a vertex whose weights sum
        to zero, a negative joint index or shapes that disagree."""
        j = np.asarray(joints)
        w = np.asarray(weights, np.float64)
        if j.ndim != 2 or w.ndim != 2 or j.shape != w.shape or not 0 < j.shape[1] <= INFLUENCES:
            raise ValueError(
                f"{name}: joints and weights must both be (V, k) with k at most {INFLUENCES}, "
                f"got {j.shape} and {w.shape}"
            )
        if j.dtype.kind not in "iu":
            raise ValueError(f"{name}: joint indices must be integers, got {j.dtype}")
        bad = ~np.isfinite(w) | (w < 0)
        if bad.any():
            v = int(np.flatnonzero(bad.any(axis=1))[0])
            raise ValueError(f"{name}: vertex {v} has weights {w[v].tolist()}: each must be finite and not negative")
        if j.size and (int(j.min()) < 0 or int(j.max()) > np.iinfo(np.uint16).max):
            raise ValueError(f"{name}: joint index {int(j.min()) if j.min() < 0 else int(j.max())} is out of range")
        total = w.sum(axis=1)
        if (total <= 0).any():
            v = int(np.flatnonzero(total <= 0)[0])
            raise ValueError(f"{name}: vertex {v}'s weights sum to 0: it follows no joint")
        w = w / total[:, None]
        j = np.where(w > 0, j, 0)  # an unused influence names joint 0
        pad = INFLUENCES - j.shape[1]
        joints8 = np.pad(j.astype(np.uint16), ((0, 0), (0, pad)))
        weights8 = np.pad(w.astype(np.float32), ((0, 0), (0, pad)))
        for a in (joints8, weights8):
            a.flags.writeable = False
        return cls(joints8, weights8)

    @property
    def vertex_count(self) -> int:
        return int(self.joints.shape[0])

    def vertices(self, rows: np.ndarray) -> SkinWeights:
        """The weights of vertices `rows`, in that order (a level of detail's, a cut mesh's)."""
        return SkinWeights(self.joints[rows], self.weights[rows])

    def largest_joint(self) -> int:
        """The largest joint index a vertex uses (with a weight above 0); -1 for no vertex."""
        used = self.joints[self.weights > 0]
        return int(used.max()) if used.size else -1
