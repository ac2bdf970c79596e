"""Skins: the joints that move a skinned mesh's vertices. The world's `Skins` resource holds each
skin once (its inverse bind matrices, and how far from each joint its vertices lie) with the
joint entities of every copy of it; a mesh entity names its skin and copy with `Skinned`.

Each frame, after the hierarchy placed the joints, SkinSystem computes every copy's joint
matrices in one pass per skin: joint world matrix @ inverse bind matrix, in world space (the
glTF specification's joint matrix times the mesh node's global transform, which a skinned
mesh's vertices ignore), and a sphere holding the posed vertices. A vertex is then the
weighted sum of its joints' matrices applied to it (`skinned_positions`, the reference the GPU
is held to)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ecs_engine.components.animation import Skinned
from ecs_engine.components.hierarchy import WorldMatrix
from ecs_engine.ecs.gather import gather
from ecs_engine.ecs.schedule import System, any_with

from ..errors import UsageError


@dataclass
class Skin:
    name: str
    inverse_binds: np.ndarray  # (J, 4, 4) float64
    reach: np.ndarray  # (J,) float64: the farthest a vertex it moves lies from the joint, in bind space
    joints: np.ndarray = field(default_factory=lambda: np.empty((0, 0), np.int64))  # (copies, J) entity ids
    # what SkinSystem computed last: (copies, J, 4, 4) float64 joint matrices in world space, and
    # per copy a sphere (centre (copies, 3), radius (copies,)) around the posed vertices
    matrices: np.ndarray | None = None
    centres: np.ndarray | None = None
    radii: np.ndarray | None = None

    @property
    def joint_count(self) -> int:
        return int(self.inverse_binds.shape[0])

    @property
    def copies(self) -> int:
        return int(self.joints.shape[0])


class Skins:
    """World resource: the skins, by handle (Skinned.skin)."""

    def __init__(self) -> None:
        self.skins: list[Skin] = []

    def add(self, name: str, inverse_binds: np.ndarray, reach: np.ndarray | None = None) -> int:
        """A skin of J joints (`inverse_binds` (J, 4, 4)); `reach` (J,): see Skin. Its handle."""
        binds = np.array(inverse_binds, np.float64)
        if binds.ndim != 3 or binds.shape[1:] != (4, 4) or not len(binds) or not np.isfinite(binds).all():
            raise UsageError(f"skin {name!r}: inverse_binds must be finite (J, 4, 4) with J >= 1, not {binds.shape}")
        count = len(binds)
        reach = np.zeros(count) if reach is None else np.array(reach, np.float64).reshape(-1)
        if reach.shape != (count,) or not (np.isfinite(reach) & (reach >= 0)).all():
            raise UsageError(f"skin {name!r}: reach must be {count} finite distances, not negative")
        self.skins.append(Skin(name, binds, reach, np.empty((0, count), np.int64)))
        return len(self.skins) - 1

    def add_copies(self, skin: int, joints: np.ndarray) -> np.ndarray:
        """Copies of skin `skin` whose joints are the entities `joints` (copies, J): their copy
        numbers (Skinned.copy)."""
        s = self[skin]
        joints = np.asarray(joints, np.int64)
        if joints.ndim != 2 or joints.shape[1] != s.joint_count:
            raise UsageError(f"skin {s.name!r} has {s.joint_count} joints: copies must be (n, {s.joint_count})")
        first = s.copies
        s.joints = np.concatenate([s.joints, joints])
        s.matrices = s.centres = s.radii = None
        return np.arange(first, first + len(joints), dtype=np.int32)

    def __getitem__(self, handle: int) -> Skin:
        if isinstance(handle, bool) or not 0 <= int(handle) < len(self.skins):
            raise UsageError(f"no skin {handle!r}: the world has {len(self.skins)}")
        return self.skins[int(handle)]

    def __len__(self) -> int:
        return len(self.skins)


def joint_matrices(world: object, skin: Skin) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(matrices (copies, J, 4, 4), centres (copies, 3), radii (copies,)) of `skin`'s copies as
    the joints' WorldMatrix stands; a joint that is gone counts as the identity."""
    worlds, found = gather(world, skin.joints, WorldMatrix, "matrix")
    worlds[~found] = np.eye(4)
    matrices = worlds @ skin.inverse_binds
    # a vertex moved by joint j alone lies within reach_j * (the joint's largest axis scale) of
    # the joint's origin; a blend of joints lies in the hull of those balls
    origins = worlds[..., :3, 3]
    scale = np.linalg.norm(worlds[..., :3, :3], axis=-2).max(axis=-1)
    reach = skin.reach * scale
    low, high = (origins - reach[..., None]).min(axis=1), (origins + reach[..., None]).max(axis=1)
    centres = (low + high) / 2
    radii = (np.linalg.norm(origins - centres[:, None], axis=2) + reach).max(axis=1, initial=0.0)
    return matrices, centres, radii


class SkinSystem(System):
    """Every skin's joint matrices and pose bounds (Skin.matrices, centres, radii), after the
    hierarchy (HierarchyPlugin adds it after HierarchySystem)."""

    def __init__(self) -> None:
        super().__init__(reads=[Skins, WorldMatrix, Skinned], writes=[], name="skins", run_if=any_with(Skinned))

    def run(self, world: object, dt: float) -> None:
        skins = world.resources.get(Skins)  # type: ignore[attr-defined]
        if skins is None:
            return
        for skin in skins.skins:
            if skin.copies:
                skin.matrices, skin.centres, skin.radii = joint_matrices(world, skin)


def skinned_positions(
    positions: np.ndarray, joints: np.ndarray, weights: np.ndarray, matrices: np.ndarray
) -> np.ndarray:
    """Vertices (V, 3) moved by their joints: sum over influences of weight * (matrices[joint] @
    (position, 1)), with `joints`, `weights` (V, k) and one copy's `matrices` (J, 4, 4)."""
    p = np.c_[np.asarray(positions, np.float64), np.ones(len(positions))]
    blended = np.einsum("vk,vkij->vij", np.asarray(weights, np.float64), matrices[np.asarray(joints, np.int64)])
    return np.einsum("vij,vj->vi", blended, p)[:, :3]
