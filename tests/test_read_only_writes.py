"""A system that writes through a read-only view (a component it only reads) gets the engine's
AccessError naming the system, the component and the field (issue 33), not NumPy's bare
"assignment destination is read-only"; systems that behave pay nothing for it."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import AccessError, Component, Field, Schedule, World, system
from ecs_engine.jobs import JobPool


class Health(Component):
    hp = Field(np.float32, default=10.0)
    regen = Field(np.float32, (2,), default=(0.0, 1.0))


class Speed(Component):
    v = Field(np.float64, (3,))


def run(fn, reads=(Health,), writes=(Speed,), parallel=False):
    world = World()
    world.spawn_batch(4, Health(), Speed())
    schedule = Schedule(("update",), parallel=parallel)
    schedule.add(system(reads=reads, writes=writes, name="wounds")(fn))
    if parallel:
        world.resources[JobPool] = JobPool(2)
        schedule.add(system(writes=[], name="other")(lambda world, dt: None))
    try:
        schedule.run(world, 0.0)
    finally:
        if parallel:
            world.resources[JobPool].close()


def store(world, dt):
    for batch in world.query(Health, Speed):
        low = batch[Health].hp < 20
        batch[Health].hp[low] = 0.0


def augmented(world, dt):
    for batch in world.query(Health, Speed):
        batch[Health].hp += 1.0


def through_a_name(world, dt):
    for batch in world.query(Health, Speed):
        regen = batch[Health].regen
        regen[:, 0] = 2.0


def through_a_field_key(world, dt):
    for batch in world.query(Health, Speed):
        batch[Health.hp][1:] *= 2.0


def view_attribute(world, dt):
    for batch in world.query(Health, Speed):
        view = batch[Health]
        view.hp = 5.0


def ufunc_out(world, dt):
    for batch in world.query(Health, Speed):
        np.multiply(batch[Health].hp, 0.5, out=batch[Health].hp)


def helper(hp):
    hp[...] = 1.0  # in a function the system calls


def in_a_helper(world, dt):
    for batch in world.query(Health, Speed):
        helper(batch[Health].hp)


def multi_line(world, dt):
    for batch in world.query(Health, Speed):
        batch[Health].regen[:, 1] = 3.0


@pytest.mark.parametrize(
    "fn, field",
    [
        (store, "hp"),
        (augmented, "hp"),
        (through_a_name, "regen"),
        (through_a_field_key, "hp"),
        (view_attribute, "hp"),
        (ufunc_out, "hp"),
        (in_a_helper, "hp"),
        (multi_line, "regen"),
    ],
)
@pytest.mark.parametrize("parallel", [False, True])
def test_a_write_to_a_component_only_read_names_the_system_component_and_field(fn, field, parallel):
    with pytest.raises(
        AccessError,
        match=rf"system wounds writes Health\.{field} \(.*test_read_only_writes\.py:\d+\) "
        r"but declares Health read-only: add Health to its writes",
    ) as caught:
        run(fn, parallel=parallel)
    assert "assignment destination" not in str(caught.value) and "output array" not in str(caught.value)


def test_a_query_asked_read_only_and_the_entity_ids_are_named():
    def query_read_only(world, dt):
        for batch in world.query(Health, Speed, write=()):
            batch[Speed].v[:] = 1.0

    with pytest.raises(
        AccessError, match=r"system wounds writes Speed\.v .* through a query that asked for it read-only"
    ):
        run(query_read_only)

    def ids(world, dt):
        for batch in world.query(Health, Speed):
            batch.entities[0] = 7

    with pytest.raises(AccessError, match=r"system wounds writes batch\.entities .*: entity ids are read-only"):
        run(ids)


def test_without_source_the_system_and_its_read_only_components_are_still_named():
    namespace: dict = {}
    exec(
        "def hidden(world, dt):\n    for b in world.query(Health, Speed):\n        b[Health].hp[0] = 1\n",
        globals(),
        namespace,
    )
    with pytest.raises(AccessError, match=r"system wounds wrote to a read-only view .*read-only"):
        run(namespace["hidden"])


def test_other_value_errors_pass_unchanged():
    def bad(world, dt):
        raise ValueError("my own")

    with pytest.raises(ValueError, match=r"^my own$"):
        run(bad)
