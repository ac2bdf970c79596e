"""Parenting: an entity with `Parent` has its Transform relative to its parent's, through any
depth; `WorldMatrix` holds where it ends up in the world (float64, written by HierarchySystem,
readable by game systems: the world position of a ship's gun is its column 3).

A parent id of -1, or of a dead entity (`world.destroy(parent)` leaves its children so), makes
the child a root: its Transform is its world transform. `destroy_subtree` removes an entity with
all its descendants; `set_parent` reparents, keeping the child where it is in the world if
asked; a parent chain that loops is refused there, and reported by the system if made another
way.
"""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.errors import EcsError
from ecs_engine.ecs.schema import Component, Field
from ecs_engine.ecs.world import World
from ecs_engine.maths.decompose import decompose, trs_matrices

from .transform import Transform


class WorldMatrix(Component):
    """The entity's world transform as a float64 4x4 matrix ([row, column], column vectors)."""

    matrix = Field(np.float64, (4, 4), default=np.eye(4))


class Parent(Component):
    required = (WorldMatrix,)

    entity = Field(np.int64, default=-1, entity=True)


def parents(world: World) -> tuple[np.ndarray, np.ndarray]:
    """(children, their parents) of every entity with Parent, as id arrays."""
    children, of = [], []
    for batch in world.query(Parent, write=()):
        children.append(batch.entities)
        of.append(batch[Parent].entity)
    if not children:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    return np.concatenate(children), np.concatenate(of)


def children(world: World, entity: int) -> np.ndarray:
    """The ids of the entities whose Parent is `entity`."""
    kids, of = parents(world)
    return kids[of == int(entity)]


def descendants(world: World, entity: int) -> np.ndarray:
    """Every entity below `entity`, level by level (children, then grandchildren, ...)."""
    kids, of = parents(world)
    found: list[np.ndarray] = []
    level = np.array([int(entity)], np.int64)
    seen = {int(entity)}
    while len(level):
        level = kids[np.isin(of, level)]
        level = np.array([e for e in level.tolist() if e not in seen], np.int64)
        seen.update(level.tolist())
        found.append(level)
    return np.concatenate(found) if found else np.empty(0, np.int64)


def world_matrices(world: World, ids: np.ndarray) -> np.ndarray:
    """(n, 4, 4) world matrices of a few entities, walking up their parents now (float64; the
    system computes everyone's each frame; this is for edits between frames)."""
    out = np.zeros((len(ids), 4, 4))
    for k, entity in enumerate(np.asarray(ids).tolist()):
        matrix, seen = np.eye(4), set()
        while entity != -1 and world.is_alive(entity) and entity not in seen:
            seen.add(entity)
            t = world.get(entity, Transform)
            matrix = trs_matrices(t.position[None], t.rotation[None], t.scale[None])[0] @ matrix
            entity = int(world.get(entity, Parent).entity) if world.has(entity, Parent) else -1
        out[k] = matrix
    return out


def destroy_subtree(world: World, entity: int) -> None:
    """Destroy `entity` and all its descendants (deferred inside systems, like any destroy)."""
    world.destroy(np.concatenate([[int(entity)], descendants(world, entity)]).astype(np.int64))


def set_parent(world: World, child: int, parent: int | None, keep_world: bool = False) -> None:
    """Make `parent` the parent of `child` (None or -1: a root). With `keep_world`, the child's
    Transform is recomputed so it stays where it is in the world (a mirrored or sheared result
    keeps its nearest rotation and scale). A loop (the parent below the child) is refused."""
    target = -1 if parent is None else int(parent)
    if target != -1:
        if target == int(child) or target in set(descendants(world, child).tolist()):
            raise EcsError(f"entity {parent} is {child} itself or below it: a parent chain may not loop")
        if not world.is_alive(target):
            raise EcsError(f"entity {parent} is not alive and cannot be a parent")
    if keep_world:
        world_now = world_matrices(world, np.array([int(child)]))[0]
        parent_world = world_matrices(world, np.array([target]))[0] if target != -1 else np.eye(4)
        position, rotation, scale = decompose(np.linalg.inv(parent_world) @ world_now)
        world.set(child, Transform(position=position, rotation=rotation, scale=scale))
    if world.has(child, Parent):
        world.set(child, Parent(entity=target))
    else:
        world.add(child, Parent(entity=target))
