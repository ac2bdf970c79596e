"""Skins: the joints that move a skinned mesh's vertices. The world's `Skins` resource holds each
skin once (its inverse bind matrices, and how far from each joint its vertices lie) with the
joint entities of every copy of it; a mesh entity names its skin and copy with `Skinned`.

Each frame, after the hierarchy placed the joints, SkinSystem computes every copy's joint
matrices in one pass per skin (skin_pose.py, on the job pool's threads): joint world matrix @
inverse bind matrix (the glTF specification's joint matrix times the mesh node's global
transform, which a skinned mesh's vertices ignore), kept as float32 rows relative to the render
origin as ModelMatrix is, and a sphere holding the posed vertices. A vertex is then the
weighted sum of its joints' matrices applied to it (`skinned_positions`, the reference the GPU
is held to)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ecs_engine.components.animation import Skinned
from ecs_engine.components.camera import RenderOrigin, render_origin
from ecs_engine.components.hierarchy import WorldMatrix
from ecs_engine.components.transform import ModelMatrix
from ecs_engine.ecs.entities import INDEX_MASK
from ecs_engine.ecs.gather import gather
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.jobs import JobPool, over_rows

from ..errors import UsageError
from .skin_pose import place, pose

COPIES_PER_JOB = 512  # a job poses this many copies (24 joints: ~12k matrices)
_WORLD = (WorldMatrix, "matrix")


@dataclass
class Skin:
    name: str
    inverse_binds: np.ndarray  # (J, 4, 4) float64
    reach: np.ndarray  # (J,) float64: the farthest a vertex it moves lies from the joint, in bind space
    joints: np.ndarray = field(default_factory=lambda: np.empty((0, 0), np.int64))  # (copies, J) entity ids
    # what SkinSystem computed last: (copies, J, 3, 4) float32 joint matrices' rows relative to
    # `origin` (the render origin then), and per copy a sphere around the posed vertices, in
    # world space (centre (copies, 3), radius (copies,))
    matrices: np.ndarray | None = None
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    centres: np.ndarray | None = None
    radii: np.ndarray | None = None
    # where the joints' world matrices are: (structure version, the table's id or -1 for several
    # tables, rows (copies, J) in it, -1 for a joint that is gone)
    places: tuple[int, int, np.ndarray] | None = None

    @property
    def joint_count(self) -> int:
        return int(self.inverse_binds.shape[0])

    @property
    def copies(self) -> int:
        return int(self.joints.shape[0])

    def world_matrices(self, copy: int) -> np.ndarray:
        """Copy `copy`'s joint matrices (J, 4, 4) float64, in world space, as last computed."""
        if self.matrices is None:
            raise UsageError(f"skin {self.name!r} has not been posed yet (SkinSystem runs after the hierarchy)")
        out = np.zeros((self.joint_count, 4, 4))
        out[:, :3] = self.matrices[copy]
        out[:, :3, 3] += self.origin
        out[:, 3, 3] = 1.0
        return out


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
        s.matrices = s.centres = s.radii = s.places = None
        return np.arange(first, first + len(joints), dtype=np.int32)

    def __getitem__(self, handle: int) -> Skin:
        if isinstance(handle, bool) or not 0 <= int(handle) < len(self.skins):
            raise UsageError(f"no skin {handle!r}: the world has {len(self.skins)}")
        return self.skins[int(handle)]

    def __len__(self) -> int:
        return len(self.skins)


def joint_matrices(world: Any, skin: Skin, origin: np.ndarray, pool: Any = None) -> None:
    """Pose `skin`'s copies as the joints' WorldMatrix stands (Skin.matrices, centres, radii),
    relative to `origin`; ranges of copies on `pool`'s threads."""
    worlds, rows = _joint_worlds(world, skin)
    copies = skin.copies
    if skin.matrices is None or skin.matrices.shape[0] != copies:
        skin.matrices = np.empty((copies, skin.joint_count, 3, 4), np.float32)
        skin.centres, skin.radii = np.empty((copies, 3)), np.empty(copies)
    skin.origin = origin.copy()
    out, centres, radii = skin.matrices, skin.centres, skin.radii
    assert centres is not None and radii is not None
    binds, reach = skin.inverse_binds, skin.reach

    def chunk(s: slice) -> None:
        pose(worlds, rows, binds, reach, origin, out, centres, radii, s.start, s.stop)

    over_rows(pool, copies, chunk, chunk_rows=COPIES_PER_JOB)


def _joint_worlds(world: Any, skin: Skin) -> tuple[np.ndarray, np.ndarray]:
    """(world matrices, rows (copies, J) in them): the joints' table's WorldMatrix column when they
    all live in one table (the usual case: kept per structure version), else a gathered copy."""
    storage = world.storage
    places = skin.places
    if places is None or places[0] != storage.structure_version:
        ids = skin.joints.reshape(-1)
        alive = world.alive(ids)
        at = np.where(alive, ids & INDEX_MASK, 0)
        tables = storage.index.table[at]
        found = np.unique(tables[alive])
        one = len(found) == 1 and storage.tables[int(found[0])].has(WorldMatrix)
        rows = np.where(alive, storage.index.row[at], -1) if one else np.where(alive, np.arange(len(ids)), -1)
        table = int(found[0]) if one else -1
        places = skin.places = (storage.structure_version, table, rows.reshape(skin.joints.shape))
    if places[1] >= 0:
        return storage.tables[places[1]].columns[_WORLD], places[2]
    worlds, found = gather(world, skin.joints.reshape(-1), WorldMatrix, "matrix")
    return worlds, np.where(found, places[2].reshape(-1), -1).reshape(skin.joints.shape)


class SkinSystem(System):
    """Every skin's joint matrices and pose bounds (Skin.matrices, centres, radii), then each
    Skinned row's ModelMatrix: its mesh's sphere (Skinned.centre, radius) scaled and moved onto
    its copy's pose sphere, relative to the render origin (the renderer culls by it; the vertex
    shader draws the vertices from the joints). After the hierarchy (HierarchyPlugin)."""

    def __init__(self) -> None:
        reads = [Skins, WorldMatrix, Skinned, RenderOrigin, JobPool]
        super().__init__(reads=reads, writes=[ModelMatrix], name="skins", run_if=any_with(Skinned))

    def run(self, world: Any, dt: float) -> None:
        skins = world.resources.get(Skins)
        if skins is None:
            return
        origin = np.asarray(render_origin(world), np.float64)
        pool = world.resources.get(JobPool)
        for skin in skins.skins:
            if skin.copies:
                joint_matrices(world, skin, origin, pool)
        centres = [np.zeros((0, 3)) if s.centres is None else s.centres for s in skins.skins]
        radii = [np.zeros(0) if s.radii is None else s.radii for s in skins.skins]
        first = np.cumsum([0] + [len(r) for r in radii]).astype(np.int64)
        every_centre, every_radius = np.concatenate(centres), np.concatenate(radii)
        for batch in world.query(Skinned, ModelMatrix):
            skinned = batch[Skinned]
            place(
                skinned.skin, skinned.copy, skinned.radius, skinned.centre, first,
                every_centre, every_radius, origin, batch[ModelMatrix].model,
            )  # fmt: skip


def skinned_positions(
    positions: np.ndarray, joints: np.ndarray, weights: np.ndarray, matrices: np.ndarray
) -> np.ndarray:
    """Vertices (V, 3) moved by their joints: sum over influences of weight * (matrices[joint] @
    (position, 1)), with `joints`, `weights` (V, k) and one copy's `matrices` (J, 3 or 4, 4)."""
    p = np.c_[np.asarray(positions, np.float64), np.ones(len(positions))]
    rows = np.asarray(matrices, np.float64)[:, :3]
    blended = np.einsum("vk,vkij->vij", np.asarray(weights, np.float64), rows[np.asarray(joints, np.int64)])
    return np.einsum("vij,vj->vi", blended, p)
