"""A name an entity is shown by (the editor's entity browser and tree, saved scenes): a plain
unicode column, so names are vectorised like any field (`query.column(Name.value)`) and saved
without pickle. Names need not be unique; `find_named` returns every match."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.entities import INDEX_MASK
from ecs_engine.ecs.schema import Component, Field
from ecs_engine.ecs.world import World

NAME_LENGTH = 64  # characters; a longer name is refused where it enters the world


class Name(Component):
    value = Field(f"U{NAME_LENGTH}", default="")


def find_named(world: World, name: str) -> np.ndarray:
    """The ids of the entities called `name` (any number of them)."""
    parts = [batch.entities[batch[Name].value == name] for batch in world.query(Name, write=())]
    return np.concatenate(parts) if parts else np.empty(0, np.int64)


def name_of(world: World, entity: int) -> str:
    """The entity's Name, or "entity <index>" without one (what the editor lists)."""
    if world.has(entity, Name):
        value = str(world.get(entity, Name).value)
        if value:
            return value
    return f"entity {int(entity) & INDEX_MASK}"
