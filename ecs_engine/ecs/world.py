"""The world: the API over the storage. It checks values where they enter (input_checks.py),
defers structural changes while systems and query loops run (deferral.py, with a typed command
queue, see commands.py), hands out cached queries and keeps the change ticks of the running
system."""

from __future__ import annotations

import threading
from collections.abc import Iterable
from typing import Any

import numpy as np

from .commands import Add, CommandQueue, Destroy, Remove, Set, Spawn
from .deferral import Deferral
from .entities import INDEX_MASK
from .errors import AccessError, EcsError, MissingComponentError, describe_entity
from .events import Events
from .input_checks import checked_components, checked_ids, entity_id, new_entity, who_of
from .observing import Observing
from .query import Query, check_access
from .reactions import Reactions
from .running import Running, RunningSystem
from .schema import Component, ObjectStore, closure, object_component, refuse_non_component, schema_of
from .stage_ids import StageIds
from .storage import Checked, Storage
from .table import ArchetypeTable


class World(Observing, Deferral):
    """Holds every entity and component. See the package docstring for the rules of use."""

    def __init__(self) -> None:
        self.storage = Storage()
        self._queries: dict[tuple[Any, ...], Query] = {}
        self._queries_by_call: dict[tuple[Any, ...], Query] = {}  # as called (see query)
        self._stamp_keys: dict[tuple[type, ...], tuple[frozenset[Any], list[tuple[Any, str]]]] = {}  # change_stamp
        self._closures: dict[frozenset[type[Component]], frozenset[type[Component]]] = {}
        self.tick = 0
        self._queue = CommandQueue()
        self._local = Running()
        self._defer_depth = 0
        self._ids_lock = threading.Lock()  # id allocation by systems running in parallel
        self._stage: tuple[int, StageIds | None] | None = None  # (systems, ids) while a stage runs
        self._events: dict[type, Events[Any]] = {}
        # Singletons shared by systems (render origin, input state, ...), keyed by type.
        self.resources: dict[Any, Any] = {}
        self._reactions: Reactions | None = None  # observers, removal channels, one-shots: made on first use
        self._held = 0  # observers_held blocks open

    # ------------------------------------------------------------------ state
    def __len__(self) -> int:
        """Entities placed in tables (spawns still deferred are not counted)."""
        return sum(t.count for t in self.storage.tables)

    @property
    def tables(self) -> tuple[ArchetypeTable, ...]:
        return tuple(self.storage.tables)

    @property
    def structure_version(self) -> int:
        """Bumped by every spawn, destroy, add and remove that is applied (not when queued)."""
        return self.storage.structure_version

    def running_system(self) -> RunningSystem | None:
        """The system running on this thread, if any."""
        return self._local.system

    def entities(self) -> np.ndarray:
        parts = [t.entities[: t.count] for t in self.storage.tables if t.count]
        return np.concatenate(parts) if parts else np.empty(0, dtype=np.int64)

    def memory_bytes(self) -> int:
        """Bytes held by columns, id columns and the entity index."""
        return self.storage.nbytes()

    def shrink_to_fit(self) -> None:
        """Release the spare capacity that growth by doubling leaves behind."""
        self.storage.shrink_to_fit()

    def is_alive(self, eid: int) -> bool:
        eid = entity_id(eid)
        index = self.storage.index
        return index.valid_one(eid) and int(index.table[eid & INDEX_MASK]) >= 0

    def alive(self, ids: Any) -> np.ndarray:
        """Per id (an int array), whether it names a live entity (vectorised is_alive)."""
        ids = np.asarray(ids, np.int64).reshape(-1)
        index = self.storage.index
        ok = index.valid(ids)
        return ok & (index.table[np.where(ok, ids & INDEX_MASK, 0)] >= 0)

    def locate(self, eid: int) -> tuple[ArchetypeTable, int]:
        """The table and row holding a live entity (valid until the next structural change).
        Not inside a system that declares its access: the table's columns are open to any read
        or write, which no access check could follow (use get, set and queries there)."""
        system = self._local.system
        if system is not None and system.reads is not None and system.writes is not None:
            raise AccessError(
                f"system {system.name} called world.locate(): its table is open to reads and writes that its "
                "declared access cannot cover; use world.get, world.set or a query"
            )
        return self.storage.locate(entity_id(eid))

    def has(self, eid: int, component_type: type) -> bool:
        table, _ = self.storage.locate(entity_id(eid))
        return table.has(schema_of(component_type))

    def components(self, eid: int) -> tuple[type[Component], ...]:
        table, _ = self.storage.locate(entity_id(eid))
        return table.types

    def change_stamp(self, eid: int, *component_types: type) -> tuple[int, ...]:
        """A value that stays equal while none of these components of this entity can have
        changed: where it lives (table, row, layout) and the last write tick of each column.
        Ticks belong to tables, not rows, so a write to another entity of the same table changes
        the stamp too (never the reverse). For caching what is derived from one entity."""
        table, row = self.storage.located(eid if type(eid) is int else entity_id(eid))
        kept = self._stamp_keys.get(component_types)
        if kept is None:
            cts = [schema_of(t) for t in component_types]
            kept = self._stamp_keys[component_types] = (frozenset(cts), [(ct, n) for ct in cts for n in ct.__fields__])
        schemas, keys = kept
        system = self._local.system
        if system is not None and system.reads is not None and system.writes is not None:
            for ct in schemas - system.reads if not schemas <= system.reads else ():
                self._check_read_access(ct, "change_stamp")
        ticks = table.column_ticks
        try:
            return (table.id, table.version, row, *[ticks[k] for k in keys])
        except KeyError:
            missing = next(ct for ct in map(schema_of, component_types) if not table.has(ct))
            raise MissingComponentError(f"{describe_entity(int(eid))} has no {missing.__name__}") from None

    # ----------------------------------------------------------------- ticks
    def write_tick(self) -> int:
        """The change tick for a write now: the running system's, else a new one."""
        if self._local.system is not None:
            return self._local.tick
        self.tick += 1
        return self.tick

    def system_last_run_tick(self) -> int:
        if self._local.system is None:
            raise EcsError("a `changed` filter outside a system needs an explicit since=tick")
        return self._local.system.last_run_tick

    # ------------------------------------------------------------ checking
    def _ids(self, target: Any, allow_reserved: bool = False) -> np.ndarray:
        return checked_ids(self.storage, target, allow_reserved, self._commands.pending_destroy)

    def _check_read_access(self, ct: type[Component], call: str) -> None:
        system = self._local.system
        if system is None or system.reads is None or system.writes is None:
            return  # outside systems, or one that may read anything (it runs alone)
        if ct not in system.reads and ct not in system.writes:
            raise AccessError(f"system {system.name} reads {ct.__name__} (world.{call}) but does not declare it")

    def _check_write_access(self, ct: type[Component]) -> None:
        system = self._local.system
        if system is not None and system.writes is not None and ct not in system.writes:
            raise AccessError(f"system {system.name} writes {ct.__name__} but does not declare it")

    # ----------------------------------------------------------------- spawn
    def spawn(self, *values: Any) -> int:
        """Create one entity from component values; returns its id."""
        checked = checked_components(values, 1, new_entity, "spawn()", 1)
        types = self._closure(checked)
        if self.deferring:
            ids = self._reserve(1)
            self._commands.push(Spawn(ids, types, checked))
            return int(ids[0])
        eid = self.storage.index.allocate_one() if self._stage is None else int(self._reserve(1)[0])
        self.storage.place_one(eid, types, checked, self.write_tick())
        if self._reactions is not None:
            self._react()
        return eid

    def _closure(self, checked: Checked) -> frozenset[type[Component]]:
        key = frozenset(checked)
        types = self._closures.get(key)
        if types is None:
            types = self._closures[key] = frozenset(closure(set(key)))
        return types

    def spawn_batch(self, n: int, *values: Component) -> np.ndarray:
        """Create n entities in one call; field values may be shared or given per row."""
        n = int(n)
        if n < 0:
            raise ValueError(f"cannot spawn a negative number of entities ({n})")
        checked = checked_components(values, n, new_entity, "spawn_batch()", 2)
        types = self._closure(checked)
        if self.deferring:
            ids = self._reserve(n)
            self._commands.push(Spawn(ids, types, checked))
        else:
            ids = self.storage.index.allocate(n) if self._stage is None else self._reserve(n)
            self.storage.place(ids, types, checked, self.write_tick())
            if self._reactions is not None:
                self._react()
        return ids

    # --------------------------------------------------------------- destroy
    def destroy(self, target: Any) -> None:
        """Destroy one entity or an array of them. Their ids never name an entity again."""
        if isinstance(target, (int, np.integer)) and not self.deferring:
            self.storage.destroy_one(entity_id(target))
            if self._reactions is not None:
                self._react()
            return
        ids = self._ids(target, allow_reserved=self.deferring)
        if not len(ids):
            return
        if self.deferring:
            self._commands.push(Destroy(ids))
            return
        self.storage.destroy(ids)
        if self._reactions is not None:
            self._react()

    # ------------------------------------------------------------ add/remove
    def add(self, target: Any, value: Any) -> None:
        """Add a component to one entity or many (rows move tables). An existing one is replaced."""
        ids = self._ids(target, allow_reserved=self.deferring)
        checked = checked_components([value], 1 if len(ids) == 1 else len(ids), who_of(ids), "add()", 2)
        ((ct, vals),) = checked.items()
        if not len(ids):
            return  # no entities: nothing to do (the value was still checked)
        if self.deferring:
            self._commands.push(Add(ids, ct, vals))
            return
        self.storage.add(ids, ct, vals, self.write_tick())
        if self._reactions is not None:
            self._react()

    def remove(self, target: Any, component_type: type) -> None:
        """Remove a component from one entity or many; raises if one of them lacks it."""
        ct = schema_of(component_type)
        ids = self._ids(target, allow_reserved=self.deferring)
        if not len(ids):
            return
        if self.deferring:
            self._commands.push(Remove(ids, ct))
            return
        self.storage.remove(ids, ct, True, self.write_tick())
        if self._reactions is not None:
            self._react()

    # --------------------------------------------------------------- get/set
    def get(self, eid: int, component_type: type) -> Any:
        """A copy of one entity's component (for a plain Python class: the stored object)."""
        eid = entity_id(eid)
        ct = schema_of(component_type)
        system = self._local.system
        if system is not None and system.reads is not None and ct not in system.reads:
            self._check_read_access(ct, "get")
        table, row = self.storage.locate(eid)
        if not table.has(ct):
            raise MissingComponentError(f"{describe_entity(eid)} has no {ct.__name__}")
        if issubclass(ct, ObjectStore):
            return table.columns[(ct, "value")][row]
        out = ct.__new__(ct)
        for name, f in ct.__fields__.items():
            v = table.columns[(ct, name)][row]
            setattr(out, name, v if f.is_object else v.copy() if f.shape else v.item())
        return out

    def set(self, target: Any, value: Any, /, **fields: Any) -> None:
        """Overwrite a component of one entity or many.

        `set(e, Transform(...))` replaces every field; `set(e, Transform, position=p)` only the
        named ones. The entities must already have the component.
        """
        if isinstance(value, type):
            ct = schema_of(value)
            if not fields:
                raise TypeError(f"set({ct.__name__}, ...) needs field=value arguments")
            unknown = set(fields) - set(ct.__fields__)
            if unknown:
                raise TypeError(f"{ct.__name__} has no field(s) {sorted(unknown)}")
            raw = fields
        else:
            if fields:
                raise TypeError("give either a component value or a type with field=value arguments")
            if isinstance(value, Component):
                ct = type(value)
                raw = value.values()
            else:
                refuse_non_component(value, "set()", 2)
                ct = object_component(type(value))
                raw = {"value": value}
        self._check_write_access(ct)
        ids = self._ids(target, allow_reserved=self.deferring)
        n = len(ids)
        who = who_of(ids)
        vals = {name: ct.__fields__[name].coerce(v, n, who) for name, v in raw.items()}
        if not n:
            return  # no entities: nothing to do (the values were still checked)
        storage = self.storage
        placed = storage.placed(ids).all()
        if len(vals) < len(ct.__fields__) and placed and storage.all_have(ids, ct):
            # partial write: cross-field checks see the stored values of the other fields
            ct.check({**storage.stored(ids, ct), **vals}, who)
        elif len(vals) == len(ct.__fields__):
            ct.check(vals, who)
        # while deferring, a set waits behind earlier queued commands on these entities (a
        # queued add then a set: the set must win), or for their spawn or add
        if self.deferring and (not placed or not storage.all_have(ids, ct) or self._commands.touches(ids)):
            self._commands.push(Set(ids, ct, vals, who))  # a partial one is checked again when applied
            return
        storage.write(ids, ct, vals, self.write_tick())

    # --------------------------------------------------------------- queries
    def query(
        self,
        *required: type,
        with_: Iterable[type] = (),
        without: Iterable[type] = (),
        write: Iterable[type] | None = None,
    ) -> Query:
        """A cached query. `write` defaults to every required type outside a system and to the
        system's declared writes inside one; other columns come back read-only."""
        system = self._local.system
        fast = None
        if type(with_) is tuple and type(without) is tuple and (write is None or type(write) is tuple):
            # the same call from the same place every frame: skip resolving and checking again
            fast = (required, with_, without, write, system, None if system is None else (system.reads, system.writes))
            q = self._queries_by_call.get(fast)
            if q is not None:
                return q
        req = tuple(schema_of(t) for t in required)
        w_set = frozenset(schema_of(t) for t in with_)
        wo_set = frozenset(schema_of(t) for t in without)
        if write is None:
            writes = frozenset(req)
            if system is not None and system.writes is not None:
                writes &= system.writes
        else:
            writes = frozenset(schema_of(t) for t in write)
            extra = writes - set(req)
            if extra:
                raise ValueError(f"write={sorted(t.__name__ for t in extra)} must also be queried")
        if system is not None and system.writes is not None:
            reads = system.reads if system.reads is not None else frozenset(req)  # None: reads anything
            check_access(system.name, reads, system.writes, req, writes)
        key = (req, w_set, wo_set, writes)
        q = self._queries.get(key)
        if q is None:
            q = self._queries[key] = Query(self, self.storage.tables, req, w_set, wo_set, writes)
        if fast is not None:
            self._queries_by_call[fast] = q
        return q

    # ------------------------------------------------------------ scene files
    def save(self, path: Any, resources: Any = None) -> None:
        """Write the entities, and what the `resources` codecs save (default: the registered ones),
        to a scene file (scene_file.py: the format; no pickle)."""
        from .scene_file import save

        save(self, path, resources=resources)

    @classmethod
    def load(cls, path: Any, into: World | None = None, resources: Any = None) -> World:
        """The entities of a scene file, in a new world or `into`, its resources read by the
        `resources` codecs (default: the registered ones). SceneFileError: nothing changed."""
        from .scene_file import load

        return load(path, cls() if into is None else into, resources=resources)[0]

    # ----------------------------------------------------------------- events
    def events(self, kind: type) -> Events[Any]:
        """The event channel of `kind` (made on first use); see events.py."""
        channel = self._events.get(kind)
        if channel is None:
            channel = self._events.setdefault(kind, Events(kind, self))
        return channel

    def update_events(self) -> None:
        """The frame boundary for every channel (Schedule calls it after each frame)."""
        for channel in self._events.values():
            channel.update()
