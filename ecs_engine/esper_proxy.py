"""What esper code gets back from an `EsperWorld`: a `ComponentProxy`, one entity's component
of an engine schema read and written in place, and the KeyError subclasses
`EntityNotFoundError` / `ComponentNotFoundError` that missing entities and components raise, as
in esper. Apart from esper_world.py (the world's methods) because a proxy is the other side of
the adapter: how an engine row looks like an esper component object; esper_world re-exports
these names."""

from __future__ import annotations

from typing import Any

from .ecs.errors import DeadEntityError, MissingComponentError
from .ecs.schema import Component
from .ecs.world import World

__all__ = ["ComponentNotFoundError", "ComponentProxy", "EntityNotFoundError"]


# ---------------------------------------------------------------------------- errors
class EntityNotFoundError(DeadEntityError, KeyError):
    """The entity does not exist (destroyed or never created). A KeyError, as in esper."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class ComponentNotFoundError(MissingComponentError, KeyError):
    """The entity exists but lacks the component. A KeyError, as in esper."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def _key_error(exc: Exception) -> Exception:
    if isinstance(exc, DeadEntityError):
        return EntityNotFoundError(str(exc))
    if isinstance(exc, MissingComponentError):
        return ComponentNotFoundError(str(exc))
    return exc


# ---------------------------------------------------------------------------- proxy
class ComponentProxy:
    """One entity's component of an engine schema, read and written in place.

    ``proxy.field`` reads the entity's current row (a writable NumPy view for array fields, a
    Python scalar for shape-() fields); ``proxy.field = value`` writes through `World.set`. The
    row is looked up on every access, so the proxy survives rows moving; once the entity or the
    component is gone, access raises EntityNotFoundError / ComponentNotFoundError (KeyErrors).
    ``copy.copy`` gives another proxy of the same component, ``copy.deepcopy`` and ``_copy()`` a
    detached `Component` value. Proxies of the same component compare equal.
    """

    __slots__ = ("_entity", "_schema", "_world")

    def __init__(self, world: World, entity: int, schema: type[Component]) -> None:
        object.__setattr__(self, "_world", world)
        object.__setattr__(self, "_entity", int(entity))
        object.__setattr__(self, "_schema", schema)

    def _locate(self) -> tuple[Any, int]:
        world = self._world
        try:
            table, row = world.storage.locate(self._entity)
        except DeadEntityError as exc:
            raise EntityNotFoundError(str(exc)) from None
        if not table.has(self._schema):
            raise ComponentNotFoundError(f"entity {self._entity} no longer has {self._schema.__name__}")
        return table, row

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):  # slots not set yet (copy, pickle) or private lookups
            raise AttributeError(name)
        f = self._schema.__fields__.get(name)
        if f is None:
            raise AttributeError(f"{self._schema.__name__} has no field {name!r}")
        table, row = self._locate()
        key = (self._schema, name)
        col = table.columns[key]
        if f.shape:
            # A writable view: mark the column changed, as a writable query view does.
            table.column_ticks[key] = self._world.write_tick()
            return col[row]
        value = col[row]
        return value if f.is_object else value.item()

    def __setattr__(self, name: str, value: Any) -> None:
        if name not in self._schema.__fields__:
            raise AttributeError(f"{self._schema.__name__} has no field {name!r}")
        try:
            self._world.set(self._entity, self._schema, **{name: value})
        except (DeadEntityError, MissingComponentError) as exc:
            raise _key_error(exc) from None

    def __delattr__(self, name: str) -> None:
        raise AttributeError("component fields cannot be deleted")

    def __dir__(self) -> list[str]:
        return sorted(set(super().__dir__()) | set(self._schema.__fields__))

    def _copy(self) -> Component:
        """A detached copy of the current values (a `Component` instance)."""
        self._locate()
        return self._world.get(self._entity, self._schema)

    def __copy__(self) -> ComponentProxy:
        return ComponentProxy(self._world, self._entity, self._schema)

    def __deepcopy__(self, memo: dict[int, Any]) -> Component:
        return self._copy()  # a snapshot of the values, detached from the World

    def __reduce__(self) -> Any:
        raise TypeError("a ComponentProxy cannot be pickled; pickle proxy._copy() instead")

    def __eq__(self, other: object) -> bool:
        if isinstance(other, ComponentProxy):
            return other._world is self._world and other._entity == self._entity and other._schema is self._schema
        if isinstance(other, Component):
            return self._copy() == other
        return NotImplemented

    def __hash__(self) -> int:
        return hash((id(self._world), self._entity, self._schema))

    def __repr__(self) -> str:
        try:
            inner = repr(self._copy())
        except KeyError:
            inner = f"{self._schema.__name__} (gone)"
        return f"<proxy of entity {self._entity}: {inner}>"
