"""The object-oriented half of the esper adapter: `EsperWorld` and `Processor`.

`EsperWorld` offers esper 3.x's functions as methods over an ecs_engine `World`; schema components
come back as `ComponentProxy` objects, and missing entities/components raise the KeyError
subclasses `EntityNotFoundError` / `ComponentNotFoundError` (esper_proxy.py holds those three,
re-exported here). Kept apart from `esper_compat`, which
holds the module-level "current world" functions and re-exports these classes, so that each stays
a readable size; docs/esper.md and esper_compat's docstring describe the differences from esper.
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable, Iterator
from types import MethodType
from typing import Any
from weakref import WeakMethod, ref

import numpy as np

from .ecs.errors import DeadEntityError
from .ecs.schema import Component, ObjectStore, object_component, refuse_non_component, schema_of
from .ecs.world import World
from .esper_proxy import ComponentNotFoundError, ComponentProxy, EntityNotFoundError

__all__ = [
    "ComponentNotFoundError",
    "ComponentProxy",
    "EntityNotFoundError",
    "EsperWorld",
    "Processor",
]


# ---------------------------------------------------------------------------- component types
def _is_object(ct: type[Component]) -> bool:
    return issubclass(ct, ObjectStore)


def _key(component_type: Any) -> type[Component] | None:
    """The schema of a component class; None for anything else (an instance passed as a type),
    which esper, looking it up in dicts, finds on no entity: unhashable raises TypeError there."""
    if isinstance(component_type, type):
        return schema_of(component_type)
    hash(component_type)
    return None


def _has(table: Any, ct: type[Component] | None) -> bool:
    return ct is not None and table.has(ct)


def _name(ct: type[Component] | None, component_type: Any) -> str:
    return ct.__name__ if ct is not None else repr(component_type)


# ---------------------------------------------------------------------------- processor
class Processor:
    """Base class of processors, as in esper: define ``process(self, *args, **kwargs)``."""

    priority = 0

    def process(self, *args: Any, **kwargs: Any) -> None:
        raise NotImplementedError


# ---------------------------------------------------------------------------- world
class EsperWorld:
    """esper 3.x's functions over an ecs_engine `World` (given, or a new one)."""

    def __init__(self, world: World | None = None) -> None:
        self.world = world if world is not None else World()
        self._dead: set[int] = set()
        self._processors: list[Any] = []
        self._processors_dict: dict[type, Any] = {}
        self.process_times: dict[str, int] = {}
        self.event_registry: dict[str, set[Any]] = {}
        self._c1: dict[Any, tuple[list[Any], Any, tuple[Any, ...], tuple[int, ...]]] = {}
        self._cn: dict[Any, tuple[list[Any], Any, tuple[Any, ...], tuple[int, ...]]] = {}
        self._cache_version = -1
        self._cache_dirty = False

    # ------------------------------------------------------------------ helpers
    def _locate(self, entity: int) -> tuple[Any, int]:
        try:
            return self.world.storage.locate(int(entity))
        except DeadEntityError as exc:
            raise EntityNotFoundError(str(exc)) from None

    def _out(self, entity: int, ct: type[Component], table: Any, row: int) -> Any:
        if _is_object(ct):
            return table.columns[(ct, "value")][row]
        return ComponentProxy(self.world, entity, ct)

    def _changed(self) -> None:
        self._cache_dirty = True

    # ------------------------------------------------------------------ entities
    def create_entity(self, *components: Any) -> int:
        """Create an entity with the given component instances; returns its (64-bit) id.
        Two components of the same type: the last one wins, as in esper."""
        by_schema: dict[type[Component], Any] = {}
        for position, c in enumerate(components, 1):
            refuse_non_component(c, "create_entity()", position)
            by_schema[type(c) if isinstance(c, Component) else object_component(type(c))] = c
        eid = self.world.spawn(*by_schema.values())
        self._changed()
        return eid

    def delete_entity(self, entity: int, immediate: bool = False) -> None:
        """Delete an entity: at the next `process`/`clear_dead_entities`, or now if
        ``immediate``. Raises KeyError at once if the entity does not exist."""
        entity = int(entity)
        if entity in self._dead and self.world.is_alive(entity):
            if not immediate:
                return
        else:
            self._locate(entity)
        if immediate:
            self._dead.discard(entity)
            self.world.destroy(entity)
            self._changed()
        else:
            self._dead.add(entity)

    def entity_exists(self, entity: int) -> bool:
        """True for a live entity not queued for deletion."""
        try:
            return self.world.is_alive(int(entity)) and int(entity) not in self._dead
        except (TypeError, ValueError, OverflowError):
            return False

    def get_entities(self) -> Iterator[int]:
        """Every live entity id (including those queued for deletion), in table order."""
        yield from self.world.entities().tolist()

    def clear_dead_entities(self) -> None:
        """Destroy the entities queued by `delete_entity`."""
        if not self._dead:
            return
        alive = [e for e in self._dead if self.world.is_alive(e)]
        self._dead.clear()
        if alive:
            self.world.destroy(np.array(alive, dtype=np.int64))
        self._changed()

    def clear_database(self) -> None:
        """Destroy every entity of the World (processors stay). Ids are not reused."""
        ids = self.world.entities()
        self._dead.clear()
        if len(ids):
            self.world.destroy(ids)
        self._changed()

    # ------------------------------------------------------------------ components
    def component_for_entity(self, entity: int, component_type: type) -> Any:
        """The entity's component of this type; KeyError if either is missing."""
        table, row = self._locate(entity)
        ct = _key(component_type)
        if ct is None or not table.has(ct):
            raise ComponentNotFoundError(f"entity {int(entity)} has no {_name(ct, component_type)}")
        return self._out(int(entity), ct, table, row)

    def components_for_entity(self, entity: int) -> tuple[Any, ...]:
        """All the entity's components (table order); KeyError if it does not exist."""
        table, row = self._locate(entity)
        return tuple(self._out(int(entity), ct, table, row) for ct in table.types)

    def has_component(self, entity: int, component_type: type) -> bool:
        table, _ = self._locate(entity)
        return _has(table, _key(component_type))

    def has_components(self, entity: int, *component_types: type) -> bool:
        table, _ = self._locate(entity)
        return all(_has(table, _key(t)) for t in component_types)

    def try_component(self, entity: int, component_type: type) -> Any | None:
        """The component, or None if the entity does not exist or lacks it."""
        try:
            table, row = self.world.storage.locate(int(entity))
        except DeadEntityError:
            return None
        ct = _key(component_type)
        return self._out(int(entity), ct, table, row) if ct is not None and table.has(ct) else None

    def try_components(self, entity: int, *component_types: type) -> tuple[Any, ...] | None:
        """The components, or None if the entity does not exist or lacks one of them."""
        try:
            table, row = self.world.storage.locate(int(entity))
        except DeadEntityError:
            return None
        cts = [_key(t) for t in component_types]
        if not all(_has(table, ct) for ct in cts):
            return None
        return tuple(self._out(int(entity), ct, table, row) for ct in cts if ct is not None)

    def add_component(self, entity: int, component_instance: Any, type_alias: type | None = None) -> None:
        """Add a component (replacing one of the same type), optionally under ``type_alias``."""
        value = component_instance
        refuse_non_component(value, "add_component()", 2)
        if type_alias is not None:
            if not isinstance(type_alias, type):
                raise TypeError(f"type_alias must be a class, got {type_alias!r}")
            if issubclass(type_alias, Component):
                if not isinstance(value, type_alias):
                    raise TypeError(
                        f"type_alias {type_alias.__name__} is an engine schema: the instance must be "
                        f"a {type_alias.__name__} (or a subclass), got {type(value).__name__}"
                    )
                if type(value) is not type_alias:
                    value = type_alias(**{n: getattr(value, n) for n in type_alias.__fields__})
            else:
                value = object_component(type_alias)(value=value)
        self._locate(entity)
        self.world.add(int(entity), value)
        self._changed()

    def remove_component(self, entity: int, component_type: type) -> Any:
        """Remove a component and return it (a plain object itself; a schema as a copy)."""
        ct = _key(component_type)
        table, row = self._locate(entity)
        if ct is None or not table.has(ct):
            raise ComponentNotFoundError(f"entity {int(entity)} has no {_name(ct, component_type)} to remove")
        old = table.columns[(ct, "value")][row] if _is_object(ct) else self.world.get(int(entity), ct)
        self.world.remove(int(entity), ct)
        self._changed()
        return old

    def try_remove_component(self, entity: int, component_type: type) -> Any | None:
        """Like `remove_component`, but None when the entity lacks the component (a missing
        entity still raises KeyError, as esper does once the type is in use)."""
        table, _ = self._locate(entity)
        if not _has(table, _key(component_type)):
            return None
        return self.remove_component(entity, component_type)

    # ------------------------------------------------------------------ queries
    def clear_cache(self) -> None:
        """Drop the get_component(s) cache (never needed; for benchmarks and debugging)."""
        self._cache_dirty = True

    def _check_cache(self) -> None:
        version = self.world.structure_version
        if self._cache_dirty or version != self._cache_version:
            self._c1.clear()
            self._cn.clear()
            self._cache_version = version
            self._cache_dirty = False

    @staticmethod
    def _stamp(query: Any, object_keys: tuple[Any, ...]) -> tuple[int, ...]:
        # Plain objects are cached by identity: a World.set/add that replaces one (no structural
        # change) is seen through the column's write tick.
        if not object_keys:
            return ()
        return tuple(t.column_ticks[k] for t in query.tables for k in object_keys)

    def _lookup(self, cache: dict[Any, Any], key: Any) -> list[Any] | None:
        self._check_cache()
        entry = cache.get(key)
        if entry is not None:
            result, query, object_keys, stamp = entry
            if self._stamp(query, object_keys) == stamp:
                return result
        return None

    def _build(self, types: tuple[type, ...], single: bool) -> tuple[list[Any], Any, tuple[Any, ...]]:
        keys = [_key(t) for t in types]
        schemas = [ct for ct in keys if ct is not None]
        if len(schemas) < len(keys):
            return [], None, ()  # no entity has an instance as a component type, as in esper
        query = self.world.query(*schemas, write=())
        world = self.world
        out: list[Any] = []
        for batch in query:
            ids = batch.entities.tolist()
            cols = []
            for ct in schemas:
                if _is_object(ct):
                    cols.append(batch[ct].tolist())
                else:
                    cols.append([ComponentProxy(world, e, ct) for e in ids])
            if single:
                out.extend(zip(ids, cols[0]))
            else:
                out.extend(zip(ids, zip(*cols)))
        object_keys = tuple(dict.fromkeys((ct, "value") for ct in schemas if _is_object(ct)))
        return out, query, object_keys

    def get_component(self, component_type: type) -> list[tuple[int, Any]]:
        """[(entity, component)] for every entity with this component (cached)."""
        cached = self._lookup(self._c1, component_type)
        if cached is not None:
            return cached
        result, query, keys = self._build((component_type,), single=True)
        self._c1[component_type] = (result, query, keys, self._stamp(query, keys))
        return result

    def get_components(self, *component_types: type) -> list[tuple[int, tuple[Any, ...]]]:
        """[(entity, (components...))] for every entity with all these components (cached)."""
        if not component_types:
            return []
        cached = self._lookup(self._cn, component_types)
        if cached is not None:
            return cached
        result, query, keys = self._build(component_types, single=False)
        self._cn[component_types] = (result, query, keys, self._stamp(query, keys))
        return result

    # ------------------------------------------------------------------ processors
    def add_processor(self, processor_instance: Any, priority: int = 0) -> None:
        """Add a processor; higher priority runs first (equal priorities: order added)."""
        processor_instance.priority = priority
        self._processors.append(processor_instance)
        self._processors.sort(key=lambda proc: proc.priority, reverse=True)
        self._processors_dict[type(processor_instance)] = processor_instance

    def remove_processor(self, processor_type: type) -> None:
        processor = self._processors_dict.pop(processor_type, None)
        if processor is not None:
            self._processors.remove(processor)

    def get_processor(self, processor_type: type) -> Any | None:
        return self._processors_dict.get(processor_type)

    def process(self, *args: Any, **kwargs: Any) -> None:
        """Destroy entities queued for deletion, then run every processor in priority order."""
        self.clear_dead_entities()
        for processor in list(self._processors):
            processor.process(*args, **kwargs)

    def timed_process(self, *args: Any, **kwargs: Any) -> None:
        """`process`, recording each processor's CPU time (ms, int) in ``process_times``."""
        self.clear_dead_entities()
        for processor in list(self._processors):
            start = _time.process_time()
            processor.process(*args, **kwargs)
            self.process_times[processor.__class__.__name__] = int((_time.process_time() - start) * 1000)

    # ------------------------------------------------------------------ events
    def set_handler(self, name: str, func: Callable[..., Any]) -> None:
        """Register a handler for an event; only a weak reference is kept, as in esper."""
        handlers = self.event_registry.setdefault(name, set())
        registry = self.event_registry

        def forget(weak: Any) -> None:
            live = registry.get(name)
            if live is not None:
                live.discard(weak)
                if not live:
                    del registry[name]

        if isinstance(func, MethodType):
            handlers.add(WeakMethod(func, forget))
        else:
            handlers.add(ref(func, forget))

    def remove_handler(self, name: str, func: Callable[..., Any]) -> None:
        """Unregister a handler (functions and bound methods); unknown ones pass silently."""
        handlers = self.event_registry.get(name)
        if not handlers:
            return
        for weak in list(handlers):
            if weak() == func:
                handlers.discard(weak)
        if not handlers:
            del self.event_registry[name]

    def dispatch_event(self, name: str, *args: Any) -> None:
        """Call every live handler of the event with ``args``."""
        for weak in list(self.event_registry.get(name, ())):
            func = weak()
            if func is not None:
                func(*args)
