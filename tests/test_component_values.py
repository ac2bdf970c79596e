"""Only component values enter the world (issue 33): a Component value, or an instance of a
class of the user's own (stored as objects, what the esper adapter builds on). None, strings,
numbers, bools, builtin containers, NumPy values and classes are refused where they enter, with
the argument's position and what it was, and the world is left as it was."""

from __future__ import annotations

import re
from collections import namedtuple
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import Transform
from ecs_engine.ecs import schema
from ecs_engine.esper_world import EsperWorld

NOT_COMPONENTS = {
    "None": (None, "None"),
    "str": ("hp", "a str ('hp')"),
    "bytes": (b"hp", "a bytes (b'hp')"),
    "float": (1.5, "a float (1.5)"),
    "int": (3, "an int (3)"),
    "bool": (True, "a bool (True)"),
    "complex": (1j, "a complex (1j)"),
    "decimal": (Decimal("2.5"), "a Decimal (Decimal('2.5'))"),
    "fraction": (Fraction(1, 3), "a Fraction (Fraction(1, 3))"),
    "numpy scalar": (np.float32(2.0), "a float32 (2.0)"),
    "numpy bool": (np.bool_(False), "a bool (False)"),
    "list": ([1, 2], "a list ([1, 2])"),
    "tuple": ((1, 2), "a tuple ((1, 2))"),
    "dict": ({"hp": 1}, "a dict ({'hp': 1})"),
    "set": ({1}, "a set ({1})"),
    "frozenset": (frozenset(), "a frozenset (frozenset())"),
    "array": (np.zeros(3), "a NumPy array of shape (3,)"),
    "function": (len, "a builtin_function_or_method"),
}


def calls(world: World, esper: EsperWorld, e: int):
    """Each way a component enters, with the position its value has in the call."""
    return {
        "spawn": (lambda v: world.spawn(Transform(), v), "spawn", 2),
        "spawn_batch": (lambda v: world.spawn_batch(3, Transform(), v), "spawn_batch", 3),
        "add": (lambda v: world.add(e, v), "add", 2),
        "add to many": (lambda v: world.add(np.array([e]), v), "add", 2),
        "set": (lambda v: world.set(e, v), "set", 2),
        "esper create_entity": (lambda v: esper.create_entity(Transform(), v), "create_entity", 2),
        "esper add_component": (lambda v: esper.add_component(e, v), "add_component", 2),
    }


@pytest.mark.parametrize(
    "call", ["spawn", "spawn_batch", "add", "add to many", "set", "esper create_entity", "esper add_component"]
)
@pytest.mark.parametrize("kind", list(NOT_COMPONENTS))
def test_values_that_are_not_components_are_refused_naming_the_argument(call, kind):
    world = World()
    esper = EsperWorld(world)
    e = world.spawn(Transform(position=(1.0, 2.0, 3.0)))
    before = (len(world), set(schema._object_schemas), [t.types for t in world.tables])
    fn, name, position = calls(world, esper, e)[call]
    value, said = NOT_COMPONENTS[kind]
    with pytest.raises(TypeError, match=rf"^{name}\(\): argument {position} is {re.escape(said)}.*not a component"):
        fn(value)
    assert (len(world), set(schema._object_schemas), [t.types for t in world.tables]) == before
    assert world.components(e) == (Transform,) and world.get(e, Transform).position.tolist() == [1.0, 2.0, 3.0]


@pytest.mark.parametrize("call", ["spawn", "spawn_batch", "add", "esper create_entity", "esper add_component"])
def test_a_class_instead_of_an_instance_is_named(call):
    world = World()
    e = world.spawn(Transform())
    fn, name, position = calls(world, EsperWorld(world), e)[call]
    said = rf"^{name}\(\): argument {position} is the class Transform: pass .*Transform\(\)"
    with pytest.raises(TypeError, match=said):
        fn(Transform)


def test_plain_classes_of_the_users_own_stay_components():
    @dataclass
    class Score:
        points: int

    Pair = namedtuple("Pair", "a b")

    class Path(list):
        """A subclass of a builtin container, defined by the user: a component like any class."""

    class Nothing:
        pass

    world = World()
    values = [Score(3), Pair(1, 2), Path([1, 2]), Nothing()]
    e = world.spawn(Transform(), *values)
    assert [world.get(e, type(v)) for v in values] == values
    f = world.spawn()
    world.add(f, Score(4))
    world.set(f, Score(5))
    assert world.get(f, Score) == Score(5)
    esper = EsperWorld(world)
    g = esper.create_entity(Pair(3, 4))
    esper.add_component(g, Nothing())
    assert esper.has_components(g, Pair, Nothing)
