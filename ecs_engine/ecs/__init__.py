"""The ECS core: entities, component schemas, archetype storage, the world, queries, systems,
the schedule and the fixed step, and the game structure built on them (states, observers,
removal detection, one-shot systems, prefabs). It imports nothing from rendering, the app, or
the stock components and systems (they build on it)."""

from typing import TYPE_CHECKING, Any

from .errors import AccessError, DeadEntityError, EcsError, MissingComponentError
from .events import Columns, Events, Reader
from .observers import Observer, OnAdd, OnChange, OnRemove, Trigger
from .one_shot import run_once
from .query import Batch, ComponentView, Query
from .removals import Removals
from .schedule import FunctionSystem, Schedule, System, any_with, system
from .schema import Component, Field, schema_of
from .states import NextState, State, current_state, in_state, init_state, request_state
from .timestep import FixedTimestep, Interpolation
from .world import World

if TYPE_CHECKING:
    from .prefabs import Prefab, spawn_prefab


def __getattr__(name: str) -> Any:
    """Prefabs read scene files: their module (zip, JSON) is imported when first asked for."""
    if name in ("Prefab", "spawn_prefab"):
        from . import prefabs

        return getattr(prefabs, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "AccessError",
    "Batch",
    "Columns",
    "Component",
    "ComponentView",
    "DeadEntityError",
    "EcsError",
    "Events",
    "Field",
    "FixedTimestep",
    "FunctionSystem",
    "Interpolation",
    "MissingComponentError",
    "NextState",
    "Observer",
    "OnAdd",
    "OnChange",
    "OnRemove",
    "Prefab",
    "Query",
    "Reader",
    "Removals",
    "Schedule",
    "State",
    "System",
    "Trigger",
    "World",
    "any_with",
    "current_state",
    "in_state",
    "init_state",
    "request_state",
    "run_once",
    "schema_of",
    "spawn_prefab",
    "system",
]
