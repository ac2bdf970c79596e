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


class HierarchySystem(System):
    def __init__(self) -> None:
        super().__init__(reads=[Transform, Parent, RenderOrigin], writes=[WorldMatrix, ModelMatrix], name="hierarchy")

    def run(self, world: World, dt: float) -> None:
        ids, of, local = [], [], []
        for batch in world.query(Parent, Transform, write=()):
            t = batch[Transform]
            ids.append(batch.entities)
            of.append(batch[Parent].entity)
            local.append(trs_matrices(t.position, t.rotation, t.scale))
        for batch in world.query(Parent, without=(Transform,), write=()):  # no Transform: identity
            ids.append(batch.entities)
            of.append(batch[Parent].entity)
            local.append(np.broadcast_to(np.eye(4), (len(batch), 4, 4)))
        if not ids:
            return
        kids, parent_ids, locals_ = np.concatenate(ids), np.concatenate(of), np.concatenate(local)
        parent_ids = np.where((parent_ids != -1) & world.alive(parent_ids), parent_ids, -1)
        order = np.argsort(kids)
        sorted_kids = kids[order]
        found = _lookup(sorted_kids, parent_ids)
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
        worlds = np.empty_like(locals_)
        for rows in levels(parent_row, kids):
            above = np.broadcast_to(np.eye(4), (len(rows), 4, 4)).copy()
            inner = parent_row[rows] >= 0
            above[inner] = worlds[parent_row[rows][inner]]
            root_at = _lookup(roots, parent_ids[rows])
            outer = ~inner & (root_at >= 0)
            above[outer] = root_world[root_at[outer]]
            worlds[rows] = above @ locals_[rows]
        origin = render_origin(world)
        for batch in world.query(WorldMatrix, with_=(Parent,)):
            batch[WorldMatrix].matrix = worlds[order[_lookup(sorted_kids, batch.entities)]]
        for batch in world.query(ModelMatrix, with_=(Parent,)):  # what is drawn
            relative = worlds[order[_lookup(sorted_kids, batch.entities)]]
            relative[:, :3, 3] -= origin  # in float64, before the cast
            batch[ModelMatrix].model = relative.astype(np.float32)
