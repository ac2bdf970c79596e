"""What a level of detail of a skinned or morphed mesh gets wrong once it moves (mesh_lod.py).

lod_error.py measures a level in the mesh's rest shape. A skinned tube is straight at rest: its
middle rings collapse into its end rings at no error at all, and bent at its joint the level
then folds where the mesh curves. So a deformed mesh's level also carries the error its
collapses make when the mesh moves, bounded per collapsed vertex by what it no longer follows:

- **skin**: the share of its weights its survivor does not have (half the L1 distance of the two
  weight vectors, 0 to 1) times its distance from the survivor: under a joint turned by up to
  about a radian the vertex would have gone that far from where the survivor takes it;
- **morph targets**: the largest difference of its deltas and its survivor's, at weight 1.

The level's error is the larger of this and the rest shape's, so the rule that picks levels by
projected error keeps a deformed mesh at full detail until what a pose could move is under a
pixel.

So that the levels have little of this error to begin with, a skinned mesh is simplified in
regions (`joint_regions`): each triangle belongs to the joint with the most weight over its
corners, a vertex that triangles of several joints share is copied once per joint, and the
simplifier keeps the open borders this makes (with the mesh's own) where they are. No collapse
crosses from one joint's region into another's, where the weights change most. The character
demo's quarter level (of 2,880 triangles), merged across its joints, had 720 triangles and an
error of 0.19 m, all of it what moving would fold; kept apart, 742 triangles and 0.11 m (its
rest shape's; moving, 0.063 m). The seams cost a level some triangles (a
region's border stays whole), and the copies are drawn as the split vertices of a UV seam
are: the same position, weights and normal each side."""

from __future__ import annotations

import numpy as np

from .mesh_data import MeshData


def deform_error(mesh: MeshData, weld: np.ndarray, positions: np.ndarray, root: np.ndarray) -> float:
    """The bound above for one level: `weld` (render vertex -> welded vertex), the welded
    `positions` and `root` (welded vertex -> the welded vertex it collapsed into, itself for a
    survivor), as mesh_lod.py has them. 0 for a mesh neither skinned nor morphed."""
    if mesh.skin is None and mesh.morph is None:
        return 0.0
    first = np.zeros(len(positions), np.int64)  # a render vertex of each welded vertex
    first[weld[::-1]] = np.arange(len(weld))[::-1]
    gone = np.flatnonzero(root != np.arange(len(root)))
    if not len(gone):
        return 0.0
    src, dst = first[gone], first[root[gone]]
    error = 0.0
    if mesh.skin is not None:
        joints = mesh.skin.joints.astype(np.int64)
        weights = mesh.skin.weights.astype(np.float64)
        count = int(joints.max(initial=0)) + 1
        dense = np.zeros((len(gone), count))
        rows = np.arange(len(gone))[:, None]
        np.add.at(dense, (rows, joints[src]), weights[src])
        np.add.at(dense, (rows, joints[dst]), -weights[dst])
        share = 0.5 * np.abs(dense).sum(axis=1)
        distance = np.linalg.norm(positions[gone] - positions[root[gone]], axis=1)
        error = max(error, float((share * distance).max()))
    if mesh.morph is not None:
        deltas = mesh.morph.positions.astype(np.float64)  # (T, V, 3)
        error = max(error, float(np.linalg.norm(deltas[:, src] - deltas[:, dst], axis=2).max()))
    return error


#: Triangle-by-joint sums made at once by joint_regions (8 bytes each).
_REGION_CELLS = 1 << 22


def joint_regions(mesh: MeshData) -> tuple[MeshData, np.ndarray] | None:
    """A skinned `mesh` cut into its joints' regions (see the module): the same triangles, each
    vertex that triangles of several joints share copied once per joint (every attribute carried),
    and each vertex's region (its triangles' joint). None for a mesh without a skin."""
    skin = mesh.skin
    if skin is None:
        return None
    corners = mesh.indices.reshape(-1, 3).astype(np.int64)
    count = int(skin.joints.max(initial=0)) + 1
    region = np.empty(len(corners), np.int64)
    block = max(1, _REGION_CELLS // count)  # triangles summed at once: bounded memory
    for start in range(0, len(corners), block):
        part = corners[start : start + block]
        rows = np.repeat(np.arange(len(part)), 3 * skin.joints.shape[1])
        cells = rows * count + skin.joints[part].reshape(-1)
        summed = np.bincount(cells, skin.weights[part].reshape(-1).astype(np.float64), len(part) * count)
        region[start : start + len(part)] = summed.reshape(len(part), count).argmax(axis=1)  # ties: the lowest
    copies, indices = np.unique((corners * count + region[:, None]).reshape(-1), return_inverse=True)
    source = copies // count
    morph = None if mesh.morph is None else mesh.morph.vertices(source)
    cut = MeshData.from_arrays(
        mesh.positions[source], mesh.normals[source], indices.astype(np.uint32), mesh.name, mesh.uvs[source],
        tangents=mesh.tangents[source], skin=skin.vertices(source), morph=morph,
    )  # fmt: skip
    return cut, copies % count
