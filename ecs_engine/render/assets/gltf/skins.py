"""A glTF file's skins: each one's joints (nodes of the scene being read) and inverse bind
matrices, checked against the meshes it moves (a vertex naming a joint the skin lacks is the
file's error), with how far from each joint the vertices it moves lie (the pose's bounds)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh_data import MeshData
from .document import GltfDocument


@dataclass
class GltfSkin:
    index: int  # in the file's skins
    name: str
    joints: list[int]  # the joints' places in GltfScene.nodes
    inverse_binds: np.ndarray  # (J, 4, 4) float64, [row, column]
    reach: np.ndarray  # (J,) float64: the farthest a vertex it moves lies from the joint, in bind space


def read_skin(document: GltfDocument, index: int, places: dict[int, int], where: str) -> GltfSkin:
    """Skin `index` (`places`: node index -> its place in the scene's nodes; a joint outside the
    scene is an error), with reach 0 until `bind` measures the meshes it moves."""
    entry = document.item("skins", index, where)
    here = f"skins[{index}]"
    joints = entry.get("joints")
    if not isinstance(joints, list) or not joints:
        raise document.error(f"{here}.joints", "is not a non-empty array of nodes")
    out = []
    for k, node in enumerate(joints):
        if isinstance(node, bool) or not isinstance(node, int) or node not in places:
            raise document.error(f"{here}.joints[{k}]", f"is {node!r}, not a node of the scene")
        out.append(places[node])
    if len(set(out)) != len(out):
        raise document.error(f"{here}.joints", "names a node twice")
    count = len(out)
    if "inverseBindMatrices" in entry:
        at = f"{here}.inverseBindMatrices"
        binds = document.accessor(document.number(entry, "inverseBindMatrices", here), at)
        if binds.shape[1:] != (4, 4) or binds.dtype.kind != "f":
            raise document.error(at, "is not an accessor of float MAT4")
        if len(binds) != count:
            raise document.error(at, f"has {len(binds)} matrices for {count} joints")
        binds = binds.astype(np.float64)
        if not np.allclose(binds[:, 3], (0, 0, 0, 1), atol=1e-6):
            k = int(np.flatnonzero(~np.isclose(binds[:, 3], (0, 0, 0, 1), atol=1e-6).all(axis=1))[0])
            raise document.error(f"{at}[{k}]", "is not an affine matrix (its last row is not 0, 0, 0, 1)")
        if (np.abs(np.linalg.det(binds[:, :3, :3])) < 1e-18).any():
            k = int(np.flatnonzero(np.abs(np.linalg.det(binds[:, :3, :3])) < 1e-18)[0])
            raise document.error(f"{at}[{k}]", "cannot be inverted")
    else:  # the specification: identity matrices
        binds = np.broadcast_to(np.eye(4), (count, 4, 4)).copy()
    name = str(entry.get("name", f"skin{index}"))
    return GltfSkin(index, name, out, binds, np.zeros(count))


def bind(document: GltfDocument, skin: GltfSkin, mesh: MeshData, where: str) -> None:
    """Check that `mesh` (a node's primitive with skin `skin`) names only the skin's joints, and
    widen the skin's reach to its vertices."""
    weights = mesh.skin
    if weights is None:
        raise document.error(where, f"has skin {skin.index}, but its mesh's primitive has no JOINTS_0 and WEIGHTS_0")
    count = len(skin.joints)
    top = weights.largest_joint()
    if top >= count:
        raise document.error(where, f"skin {skin.index} has {count} joints, but a vertex of its mesh names joint {top}")
    # per influence: the vertex in the joint's bind space (inverse bind @ position), how far from it
    positions = np.c_[mesh.positions.astype(np.float64), np.ones(mesh.vertex_count)]
    local = np.einsum("vkij,vj->vki", skin.inverse_binds[weights.joints.astype(np.int64)], positions)[..., :3]
    distance = np.where(weights.weights > 0, np.linalg.norm(local, axis=2), 0.0)
    np.maximum.at(skin.reach, weights.joints.reshape(-1).astype(np.int64), distance.reshape(-1))
