"""World transforms through the Parent hierarchy, level by level, vectorised.

Each frame (after TransformSystem, which wrote every ModelMatrix as if each entity were a root):
the entities with Parent are sorted into levels by how many parents lie above them, then level by
level world = parent's world @ own local matrix (one batched matmul per level, float64), written
to WorldMatrix, and the ModelMatrix of every such entity is rewritten from it relative to the
render origin, in float64 before the cast (so a hierarchy 10^7 units out keeps its precision).
A child whose parent is -1 or dead is a root. A loop is an EcsError naming its entities. Ids are
matched with sorted arrays and searchsorted, never a Python loop over entities.
"""

from __future__ import annotations

import numpy as np

from ecs_engine import native
from ecs_engine.components import ModelMatrix, RenderOrigin, Transform, render_origin
from ecs_engine.components.hierarchy import Parent, WorldMatrix
from ecs_engine.ecs.errors import EcsError
from ecs_engine.ecs.schedule import System
from ecs_engine.ecs.world import World
from ecs_engine.maths.decompose import trs_matrices


def _lookup(sorted_ids: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """Positions of `ids` in `sorted_ids`, -1 where absent."""
    if not len(sorted_ids):
        return np.full(len(ids), -1, np.int64)
    at = np.minimum(np.searchsorted(sorted_ids, ids), len(sorted_ids) - 1)
    return np.where(sorted_ids[at] == ids, at, -1)


def levels(parent_row: np.ndarray, kids: np.ndarray) -> list[np.ndarray]:
    """Rows by depth: level 0 those whose parent is no hierarchy row (a root, -1 or dead), then
    their children, and so on. Raises EcsError on a loop."""
    depth = np.where(parent_row < 0, 0, -1)
    known = depth >= 0
    for level in range(1, len(kids) + 1):
        step = ~known & known[np.maximum(parent_row, 0)] & (parent_row >= 0)
        if not step.any():
            break
        depth[step] = level
        known |= step
    if not known.all():
        loop = kids[~known][:6].tolist()
        raise EcsError(f"a parent chain loops through entities {loop}: a hierarchy must end in a root")
    return [np.flatnonzero(depth == d) for d in range(int(depth.max()) + 1)] if len(depth) else []


@native.njit
def _compose(order, parent_row, root_at, position, rotation, scale, root_world, out):  # pragma: no cover - compiled
    """out[row] = (parent's world) @ T R S(row), rows taken in `order` (parents before children)."""
    m = np.empty((3, 4))
    for k in range(order.shape[0]):
        row = order[k]
        x, y, z, w = rotation[row, 0], rotation[row, 1], rotation[row, 2], rotation[row, 3]
        inv = 1.0 / np.sqrt(x * x + y * y + z * z + w * w)
        x, y, z, w = x * inv, y * inv, z * inv, w * inv
        sx, sy, sz = scale[row, 0], scale[row, 1], scale[row, 2]
        m[0, 0], m[0, 1], m[0, 2] = (1 - 2 * (y * y + z * z)) * sx, 2 * (x * y - z * w) * sy, 2 * (x * z + y * w) * sz
        m[1, 0], m[1, 1], m[1, 2] = 2 * (x * y + z * w) * sx, (1 - 2 * (x * x + z * z)) * sy, 2 * (y * z - x * w) * sz
        m[2, 0], m[2, 1], m[2, 2] = 2 * (x * z - y * w) * sx, 2 * (y * z + x * w) * sy, (1 - 2 * (x * x + y * y)) * sz
        m[0, 3], m[1, 3], m[2, 3] = position[row, 0], position[row, 1], position[row, 2]
        p = parent_row[row]
        r = root_at[row]
        for i in range(3):
            for j in range(4):
                if p >= 0:
                    v = out[p, i, 0] * m[0, j] + out[p, i, 1] * m[1, j] + out[p, i, 2] * m[2, j]
                    if j == 3:
                        v += out[p, i, 3]
                elif r >= 0:
                    v = root_world[r, i, 0] * m[0, j] + root_world[r, i, 1] * m[1, j] + root_world[r, i, 2] * m[2, j]
                    if j == 3:
                        v += root_world[r, i, 3]
                else:
                    v = m[i, j]
                out[row, i, j] = v
        out[row, 3, 0], out[row, 3, 1], out[row, 3, 2], out[row, 3, 3] = 0.0, 0.0, 0.0, 1.0


class HierarchySystem(System):
    def __init__(self) -> None:
        super().__init__(reads=[Transform, Parent, RenderOrigin], writes=[WorldMatrix, ModelMatrix], name="hierarchy")

    def run(self, world: World, dt: float) -> None:
        ids, of, position, rotation, scale, offsets = [], [], [], [], [], {}
        start = 0
        for batch in world.query(Parent, Transform, write=()):
            t = batch[Transform]
            offsets[batch.table.id] = start
            start += len(batch)
            ids.append(batch.entities)
            of.append(batch[Parent].entity)
            position.append(t.position)
            rotation.append(t.rotation)
            scale.append(t.scale)
        for batch in world.query(Parent, without=(Transform,), write=()):  # no Transform: identity
            offsets[batch.table.id] = start
            start += len(batch)
            ids.append(batch.entities)
            of.append(batch[Parent].entity)
            position.append(np.zeros((len(batch), 3)))
            rotation.append(np.broadcast_to([0.0, 0.0, 0.0, 1.0], (len(batch), 4)))
            scale.append(np.ones((len(batch), 3)))
        if not ids:
            return
        kids, parent_ids = np.concatenate(ids), np.concatenate(of)
        parent_ids = np.where((parent_ids != -1) & world.alive(parent_ids), parent_ids, -1)
        order = np.argsort(kids)
        found = _lookup(kids[order], parent_ids)
        parent_row = np.where(found >= 0, order[np.maximum(found, 0)], -1)
        # roots: live parents outside the hierarchy, their own Transform their world
        roots = np.unique(parent_ids[(parent_ids != -1) & (parent_row < 0)])
        root_world = np.broadcast_to(np.eye(4), (len(roots), 4, 4)).copy()
        for batch in world.query(Transform, without=(Parent,), write=()):
            at = _lookup(roots, batch.entities)
            rows = np.flatnonzero(at >= 0)
            if len(rows):
                t = batch[Transform]
                root_world[at[rows]] = trs_matrices(t.position[rows], t.rotation[rows], t.scale[rows])
        root_at = np.where(parent_row < 0, _lookup(roots, parent_ids), -1)
        by_level = levels(parent_row, kids)
        p, r, s = np.concatenate(position), np.concatenate(rotation), np.concatenate(scale)
        worlds = np.empty((len(kids), 4, 4))
        if native.AVAILABLE:
            _compose(np.concatenate(by_level), parent_row, root_at, p, r, s, root_world, worlds)  # type: ignore[misc]
        else:
            local = trs_matrices(p, r, s)
            for rows in by_level:
                above = np.broadcast_to(np.eye(4), (len(rows), 4, 4)).copy()
                inner = parent_row[rows] >= 0
                above[inner] = worlds[parent_row[rows][inner]]
                outer = ~inner & (root_at[rows] >= 0)
                above[outer] = root_world[root_at[rows][outer]]
                worlds[rows] = above @ local[rows]
        origin = render_origin(world)
        for batch in world.query(WorldMatrix, with_=(Parent,)):
            first = offsets[batch.table.id]
            batch[WorldMatrix].matrix = worlds[first : first + len(batch)]
        for batch in world.query(ModelMatrix, with_=(Parent,)):  # what is drawn
            first = offsets[batch.table.id]
            relative = worlds[first : first + len(batch)].copy()
            relative[:, :3, 3] -= origin  # in float64, before the cast
            batch[ModelMatrix].model = relative
