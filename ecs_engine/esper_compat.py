"""esper 3.x API over an ecs_engine World: ``import ecs_engine.esper_compat as esper``.

`EsperWorld` wraps a `World` and offers esper's functions as methods; the module-level functions
of the same names act on the current world (see `switch_world`), so ordinary esper 3 programs,
whose processors call module functions, run unchanged.

Components:

- A plain Python object (a dataclass ``Position``, ...) is stored in the object column of its
  type and handed back as the same object: identity is preserved and ``pos.x += 1`` persists.
- An instance of an engine `Component` schema (``Transform(...)``) is stored in typed NumPy
  columns and handed back as a `ComponentProxy`: ``proxy.position`` is a writable NumPy view of
  the entity's row (a Python scalar for shape-() fields); ``proxy.position = p`` writes through
  `World.set`, so values are checked (NaN, shape, range) and normalised. A proxy finds the
  entity's row on every access, so it stays correct when rows move.

Differences from esper (docs/esper.md explains each):

- Entity ids are the engine's 64-bit ids (generation << 32 | index), not 1, 2, 3...; a deleted
  id never names an entity again, and `clear_database` does not restart numbering.
- Schema components come back as proxies: a new proxy per lookup (compare with ``==``, not
  ``is``); a NumPy view read from a proxy is valid until the next structural change; writes into
  such a view are not checked, and reading an array field marks its column changed (as a
  writable query view does). `remove_component` of a schema returns a detached copy.
- Iteration order (`get_entities`, `get_component(s)`, `components_for_entity`) is table
  order, not creation order.
- `delete_entity` of an entity that does not exist raises KeyError at once (esper raises at the
  next `process`); deleting an entity twice, deferred then immediate, is harmless.
- Missing entities/components raise `EntityNotFoundError` / `ComponentNotFoundError`, which are
  both KeyError and the engine's DeadEntityError / MissingComponentError, with the engine's
  message (``str()`` is not quoted as KeyError's is).
- Required components come along (``Mesh`` brings ``ModelMatrix``); removing a component that
  another one requires raises `EcsError`.
- ``type_alias``: a plain alias stores any object in the alias's object column; a schema alias
  needs an instance of that schema (or a subclass) and stores only the alias's fields.
- Passing a class instead of an instance to `create_entity`/`add_component` raises TypeError.
- `try_remove_component` of a missing entity always raises KeyError (esper: only once some
  entity has that component type).
- `remove_handler` also removes bound-method handlers (esper 3.9 silently keeps them).
- The cache is also invalidated by changes made directly on the World (structure_version and,
  for plain-object columns, the column's write tick).
- The internals esper's own tests read are provided: ``_context_map`` (name -> EsperWorld, not
  esper's state tuples), ``_current_world``, ``_processors`` and ``_entities`` (a read-only view).
- Call these functions outside engine systems and query loops: there the World defers
  structural changes, so a new entity cannot be read until the next sync point.

This module holds the current-world state and the esper-style module functions; the classes
(`EsperWorld`, `ComponentProxy`, `Processor` and the two errors) live in `esper_world` and are
re-exported here.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from numbers import Integral
from typing import Any

from .ecs.schema import ObjectStore
from .ecs.world import World
from .esper_world import (
    ComponentNotFoundError,
    ComponentProxy,
    EntityNotFoundError,
    EsperWorld,
    Processor,
)

__all__ = [
    "ComponentNotFoundError",
    "ComponentProxy",
    "EntityNotFoundError",
    "EsperWorld",
    "Processor",
    "add_component",
    "add_processor",
    "clear_cache",
    "clear_database",
    "clear_dead_entities",
    "component_for_entity",
    "components_for_entity",
    "create_entity",
    "current_world",
    "delete_entity",
    "delete_world",
    "dispatch_event",
    "entity_exists",
    "event_registry",
    "get_component",
    "get_components",
    "get_entities",
    "get_processor",
    "get_world",
    "has_component",
    "has_components",
    "list_worlds",
    "process",
    "process_times",
    "remove_component",
    "remove_handler",
    "remove_processor",
    "set_handler",
    "switch_world",
    "timed_process",
    "try_component",
    "try_components",
    "try_remove_component",
]


# ---------------------------------------------------------------------------- module level
class _EntityMap(Mapping[int, dict[type, Any]]):
    """esper's ``_entities`` (entity -> {type: component}) as a read-only live view of one world,
    for code that reads it (esper's own tests do). Like esper's, it still holds the entities
    queued by `delete_entity` until `process`/`clear_dead_entities`."""

    def __init__(self, esper_world: EsperWorld) -> None:
        self._ew = esper_world

    def __getitem__(self, entity: int) -> dict[type, Any]:
        if entity not in self:
            raise KeyError(entity)
        values = self._ew.components_for_entity(entity)
        types = self._ew.world.components(int(entity))
        # an object column stands for the plain class (or alias) it wraps
        return {getattr(t, "wraps", t) if issubclass(t, ObjectStore) else t: v for t, v in zip(types, values)}

    def __contains__(self, entity: object) -> bool:
        try:
            return isinstance(entity, Integral) and self._ew.world.is_alive(int(entity))
        except (ValueError, OverflowError):
            return False

    def __iter__(self) -> Iterator[int]:
        return self._ew.get_entities()

    def __len__(self) -> int:
        return len(self._ew.world)


# esper's module state, under esper's names: _context_map (name -> world) and, for the current
# world, _current_world, _processors and _entities, rebound by switch_world as esper's are.
_context_map: dict[str, EsperWorld] = {"default": EsperWorld()}
_current_world: str | None = "default"
current_world: str = "default"
_current: EsperWorld = _context_map["default"]
_processors: list[Any] = _current._processors
_entities: Mapping[int, dict[type, Any]] = _EntityMap(_current)
process_times: dict[str, int] = _current.process_times
event_registry: dict[str, set[Any]] = _current.event_registry


def switch_world(name: str, world: World | EsperWorld | None = None) -> None:
    """Make the named world current, creating it if needed. Extension: ``world`` binds a new
    name to an existing engine World (or EsperWorld)."""
    global _current, _current_world, current_world, _processors, _entities, process_times, event_registry
    if _current_world is not None:
        # esper writes the current world back first: clearing _context_map forgets the others,
        # and only with _current_world = None (esper's test fixture) the current one too
        _context_map[_current_world] = _current
    if name not in _context_map:
        if world is None:
            _context_map[name] = EsperWorld()
        else:
            _context_map[name] = world if isinstance(world, EsperWorld) else EsperWorld(world)
    elif world is not None:
        bound = _context_map[name]
        if world is not bound and world is not bound.world:
            raise ValueError(f"world {name!r} exists and wraps another World")
    _current = _context_map[name]
    _current_world = current_world = name
    _processors = _current._processors
    _entities = _EntityMap(_current)
    process_times = _current.process_times
    event_registry = _current.event_registry


def list_worlds() -> list[str]:
    return list(_context_map)


def delete_world(name: str) -> None:
    """Forget a world (PermissionError for the current one, KeyError for an unknown one)."""
    if name == _current_world:
        raise PermissionError("The active World context cannot be deleted.")
    del _context_map[name]


def get_world() -> EsperWorld:
    """The current EsperWorld (its ``.world`` is the engine World)."""
    return _current


def create_entity(*components: Any) -> int:
    return _current.create_entity(*components)


def delete_entity(entity: int, immediate: bool = False) -> None:
    _current.delete_entity(entity, immediate)


def entity_exists(entity: int) -> bool:
    return _current.entity_exists(entity)


def get_entities() -> Iterator[int]:
    return _current.get_entities()


def component_for_entity(entity: int, component_type: type) -> Any:
    return _current.component_for_entity(entity, component_type)


def components_for_entity(entity: int) -> tuple[Any, ...]:
    return _current.components_for_entity(entity)


def has_component(entity: int, component_type: type) -> bool:
    return _current.has_component(entity, component_type)


def has_components(entity: int, *component_types: type) -> bool:
    return _current.has_components(entity, *component_types)


def add_component(entity: int, component_instance: Any, type_alias: type | None = None) -> None:
    _current.add_component(entity, component_instance, type_alias)


def remove_component(entity: int, component_type: type) -> Any:
    return _current.remove_component(entity, component_type)


def try_remove_component(entity: int, component_type: type) -> Any | None:
    return _current.try_remove_component(entity, component_type)


def get_component(component_type: type) -> list[tuple[int, Any]]:
    return _current.get_component(component_type)


def get_components(*component_types: type) -> list[tuple[int, tuple[Any, ...]]]:
    return _current.get_components(*component_types)


def try_component(entity: int, component_type: type) -> Any | None:
    return _current.try_component(entity, component_type)


def try_components(entity: int, *component_types: type) -> tuple[Any, ...] | None:
    return _current.try_components(entity, *component_types)


def add_processor(processor_instance: Any, priority: int = 0) -> None:
    _current.add_processor(processor_instance, priority)


def remove_processor(processor_type: type) -> None:
    _current.remove_processor(processor_type)


def get_processor(processor_type: type) -> Any | None:
    return _current.get_processor(processor_type)


def process(*args: Any, **kwargs: Any) -> None:
    _current.process(*args, **kwargs)


def timed_process(*args: Any, **kwargs: Any) -> None:
    _current.timed_process(*args, **kwargs)


def clear_database() -> None:
    _current.clear_database()


def clear_dead_entities() -> None:
    _current.clear_dead_entities()


def clear_cache() -> None:
    _current.clear_cache()


def set_handler(name: str, func: Callable[..., Any]) -> None:
    _current.set_handler(name, func)


def remove_handler(name: str, func: Callable[..., Any]) -> None:
    _current.remove_handler(name, func)


def dispatch_event(name: str, *args: Any) -> None:
    _current.dispatch_event(name, *args)
