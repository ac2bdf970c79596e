"""Names (components/name.py): a unicode column, found by value, shown for nameless entities as
their index, too-long names refused with the entity named (not silently cut)."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components.name import NAME_LENGTH, Name, find_named, name_of


def test_names_are_a_column_and_found_by_value():
    world = World()
    ship = world.spawn(Name(value="ship"))
    rocks = world.spawn_batch(3, Name(value=np.array(["rock", "rock", "big rock"])))
    plain = world.spawn()
    assert sorted(find_named(world, "rock").tolist()) == sorted(rocks[:2].tolist())
    assert find_named(world, "ship").tolist() == [ship]
    assert find_named(world, "nothing").size == 0
    assert name_of(world, ship) == "ship" and name_of(world, rocks[2]) == "big rock"
    assert name_of(world, plain) == f"entity {plain & 0xFFFFFFFF}"
    assert world.query(Name).column(Name.value).dtype == np.dtype(f"U{NAME_LENGTH}")


def test_a_name_too_long_is_refused_not_cut():
    world = World()
    longest = "x" * NAME_LENGTH
    assert world.get(world.spawn(Name(value=longest)), Name).value == longest
    with pytest.raises(ValueError, match=f"at most {NAME_LENGTH} characters"):
        world.spawn(Name(value="y" * (NAME_LENGTH + 1)))
    ids = world.spawn_batch(2, Name(value="a"))
    with pytest.raises(ValueError, match=rf"entity {ids[1]} .*at most"):
        world.set(ids, Name(value=np.array(["ok", "z" * 100])))
    assert [world.get(i, Name).value for i in ids] == ["a", "a"]  # nothing half-written
