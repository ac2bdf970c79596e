"""Property test: long random sequences of structural changes against a dict-of-dicts model.

The model maps entity id -> {component type: value}. After every step the world must hold
exactly the model's entities, each with exactly its components and values; destroyed ids
must stay dead; queries must count what the model counts.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule

from ecs_engine import Component, DeadEntityError, Field, MissingComponentError, World
from ecs_engine.ecs.schema import schema_of


class Hp(Component):
    hp = Field(np.int32, default=0)


class Pos(Component):
    xyz = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True)


class Flag(Component):
    pass


class Label:
    """A plain Python component, stored as objects."""

    def __init__(self, text: str) -> None:
        self.text = text


TYPES = [Hp, Pos, Flag, Label]
small = st.integers(-1000, 1000)


def value_of(ct, n):
    """A strategy of component values (for n entities: arrays with n rows)."""
    if ct is Hp:
        return st.lists(small, min_size=n, max_size=n).map(lambda v: Hp(hp=np.array(v)))
    if ct is Pos:
        return st.lists(st.tuples(small, small, small), min_size=n, max_size=n).map(
            lambda v: Pos(xyz=np.array(v, dtype=np.float64).reshape(n, 3))
        )
    if ct is Flag:
        return st.just(Flag())
    return st.text(max_size=3).map(Label)


def model_values(value, n):
    """Split a (possibly batched) component value into n per-entity plain values."""
    if isinstance(value, Hp):
        return [int(v) for v in np.broadcast_to(value.hp, (n,))]
    if isinstance(value, Pos):
        return [tuple(r) for r in np.broadcast_to(value.xyz, (n, 3)).tolist()]
    if isinstance(value, Flag):
        return [None] * n
    return [value] * n


def world_value(world, eid, ct):
    got = world.get(eid, ct)
    if ct is Hp:
        return int(got.hp)
    if ct is Pos:
        return tuple(got.xyz.tolist())
    if ct is Flag:
        return None
    return got


class WorldMachine(RuleBasedStateMachine):
    def __init__(self) -> None:
        super().__init__()
        self.world = World()
        self.model: dict[int, dict[type, object]] = {}
        self.dead: list[int] = []
        self.pending: list[tuple] = []  # model ops to apply at the end of a deferred block

    def alive(self):
        return sorted(self.model)

    # -------------------------------------------------------------- spawning
    @rule(data=st.data(), types=st.sets(st.sampled_from(TYPES)))
    def spawn_one(self, data, types):
        values = [data.draw(value_of(ct, 1)) for ct in types]
        eid = self.world.spawn(*values)
        assert eid not in self.model and eid not in self.dead
        self.model[eid] = {type(v) if not isinstance(v, Label) else Label: model_values(v, 1)[0] for v in values}

    @rule(data=st.data(), n=st.integers(0, 40), types=st.sets(st.sampled_from([Hp, Pos, Flag])))
    def spawn_batch(self, data, n, types):
        values = [data.draw(value_of(ct, n)) if n else ct() for ct in types]
        ids = self.world.spawn_batch(n, *values)
        per = [model_values(v, n) for v in values]
        for i, eid in enumerate(ids.tolist()):
            assert eid not in self.model and eid not in self.dead
            self.model[eid] = {type(v): per[j][i] for j, v in enumerate(values)}

    # ------------------------------------------------------------ destroying
    @precondition(lambda self: self.model)
    @rule(data=st.data())
    def destroy_some(self, data):
        pool = self.alive()
        chosen = data.draw(st.lists(st.sampled_from(pool), min_size=1, max_size=min(8, len(pool)), unique=True))
        self.world.destroy(np.array(chosen) if len(chosen) > 1 else chosen[0])
        for eid in chosen:
            del self.model[eid]
            self.dead.append(eid)

    @precondition(lambda self: self.dead)
    @rule(data=st.data())
    def stale_ids_raise(self, data):
        eid = data.draw(st.sampled_from(self.dead))
        with pytest.raises(DeadEntityError):
            self.world.destroy(eid)
        with pytest.raises(DeadEntityError):
            self.world.get(eid, Hp)
        with pytest.raises(DeadEntityError):
            self.world.add(eid, Flag())

    # ---------------------------------------------------------- add / remove
    @precondition(lambda self: self.model)
    @rule(data=st.data(), ct=st.sampled_from(TYPES))
    def add_one(self, data, ct):
        eid = data.draw(st.sampled_from(self.alive()))
        value = data.draw(value_of(ct, 1))
        self.world.add(eid, value)
        self.model[eid][ct] = model_values(value, 1)[0]

    @precondition(lambda self: len(self.model) > 1)
    @rule(data=st.data(), ct=st.sampled_from([Hp, Pos, Flag]))
    def add_many(self, data, ct):
        pool = self.alive()
        chosen = data.draw(st.lists(st.sampled_from(pool), min_size=2, max_size=min(10, len(pool)), unique=True))
        value = data.draw(value_of(ct, len(chosen)))
        self.world.add(np.array(chosen), value)
        for eid, v in zip(chosen, model_values(value, len(chosen))):
            self.model[eid][ct] = v

    @precondition(lambda self: self.model)
    @rule(data=st.data(), ct=st.sampled_from(TYPES))
    def remove_one(self, data, ct):
        eid = data.draw(st.sampled_from(self.alive()))
        if ct in self.model[eid]:
            self.world.remove(eid, ct)
            del self.model[eid][ct]
        else:
            with pytest.raises(MissingComponentError):
                self.world.remove(eid, ct)

    @precondition(lambda self: self.model)
    @rule(data=st.data())
    def set_value(self, data):
        eid = data.draw(st.sampled_from(self.alive()))
        ct = data.draw(st.sampled_from([Hp, Pos, Label]))
        value = data.draw(value_of(ct, 1))
        if ct in self.model[eid]:
            self.world.set(eid, value)
            self.model[eid][ct] = model_values(value, 1)[0]
        else:
            with pytest.raises(MissingComponentError):
                self.world.set(eid, value)

    # --------------------------------------------------------------- deferred
    @precondition(lambda self: self.model)
    @rule(data=st.data())
    def deferred_block(self, data):
        """Spawn, destroy and add inside a deferred block; the model changes at its end."""
        pool = self.alive()
        victim = data.draw(st.sampled_from(pool))
        others = [e for e in pool if e != victim]
        target = data.draw(st.sampled_from(others)) if others else None
        hp = data.draw(small)
        with self.world.deferred():
            new = self.world.spawn(Hp(hp=hp))
            self.world.destroy(victim)
            if target is not None:
                self.world.add(target, Flag())
            assert victim in self.model and self.world.is_alive(victim)  # not applied yet
            assert not self.world.is_alive(new)
        self.model[new] = {Hp: hp}
        del self.model[victim]
        self.dead.append(victim)
        if target is not None:
            self.model[target][Flag] = None

    # ------------------------------------------------------------- invariants
    @invariant()
    def world_matches_model(self):
        w = self.world
        assert len(w) == len(self.model)
        assert sorted(w.entities().tolist()) == self.alive()
        for eid, comps in self.model.items():
            assert w.is_alive(eid)
            assert set(w.components(eid)) == {schema_of(t) for t in comps}
            for ct, v in comps.items():
                assert world_value(w, eid, ct) == v, (eid, ct)
        for ct in TYPES:
            expected = sum(1 for comps in self.model.values() if ct in comps)
            assert w.query(ct, write=()).count() == expected

    @invariant()
    def dead_stay_dead(self):
        for eid in self.dead[-20:]:
            assert not self.world.is_alive(eid)


WorldMachine.TestCase.settings = settings(
    max_examples=60,
    stateful_step_count=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
TestWorldAgainstModel = WorldMachine.TestCase
