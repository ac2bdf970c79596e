"""Event channels (ecs/events.py): double-buffered per frame, each reader sees each event once,
declared like components, columns for bulk events, bad events rejected."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from ecs_engine import AccessError, Schedule, World, system
from ecs_engine.ecs import Component, Field
from ecs_engine.ecs.events import Reader


@dataclass
class Hit:
    target: int
    damage: float


class Collision(Component):
    a = Field(np.int64, default=-1, entity=True)
    b = Field(np.int64, default=-1, entity=True)
    impulse = Field(np.float32, (3,), finite=True)


def test_each_reader_sees_each_event_once_whether_it_runs_before_or_after_the_sender():
    world = World()
    seen: dict[str, list[list[int]]] = {"before": [], "after": []}

    @system(reads=[Hit])
    def before(world, dt):
        seen["before"].append([h.target for h in world.events(Hit).read()])

    @system(writes=[Hit])
    def sender(world, dt):
        frame = len(seen["before"])
        world.events(Hit).send_batch([Hit(frame * 10 + i, 1.0) for i in range(2)])

    @system(reads=[Hit])
    def after(world, dt):
        seen["after"].append([h.target for h in world.events(Hit).read()])

    schedule = Schedule(("update",))
    for s in (before, sender, after):
        schedule.add(s)
    for _ in range(3):
        schedule.run(world, 0.0)
    assert seen["after"] == [[10, 11], [20, 21], [30, 31]]  # the same frame
    assert seen["before"] == [[], [10, 11], [20, 21]]  # the next frame, never twice
    assert len(world.events(Hit)) == 2  # after the turnover: only the last frame's two are kept


def test_a_reader_two_frames_behind_loses_the_oldest_and_counts_them():
    world = World()
    channel = world.events(Hit)
    reader = Reader()
    channel.send(Hit(1, 1.0))
    world.update_events()
    channel.send(Hit(2, 1.0))
    world.update_events()
    channel.send(Hit(3, 1.0))
    assert [h.target for h in channel.read(reader)] == [2, 3]
    assert channel.dropped == 1
    assert channel.read(reader) == []
    channel.send(Hit(4, 1.0))
    assert [h.target for h in channel.read(reader)] == [4]
    assert [h.target for h in channel.read()] == [2, 3, 4]  # no reader: everything kept


def test_column_events_concatenate_and_resume_mid_batch():
    world = World()
    channel = world.events(Collision)
    reader = Reader()
    channel.send(Collision(a=np.array([1, 2, 3]), b=7, impulse=(0.0, 1.0, 0.0)))
    first = channel.read(reader)
    assert len(first) == 3 and first.a.tolist() == [1, 2, 3] and first.b.tolist() == [7, 7, 7]
    assert first.impulse.shape == (3, 3)
    channel.send(Collision(a=np.array([4, 5]), b=np.array([8, 9]), impulse=np.zeros((2, 3))))
    second = channel.read(reader)
    assert second.a.tolist() == [4, 5] and second.b.tolist() == [8, 9]
    everything = channel.read()
    assert everything.a.tolist() == [1, 2, 3, 4, 5]
    assert len(channel.read(reader)) == 0 and channel.read(reader).impulse.shape == (0, 3)


def test_events_are_checked_and_access_is_declared():
    world = World()
    with pytest.raises(ValueError, match="impulse"):
        world.events(Collision).send(Collision(a=1, b=2, impulse=(np.nan, 0.0, 0.0)))
    with pytest.raises(TypeError, match="Hit channel takes Hit events"):
        world.events(Hit).send(Collision())  # type: ignore[arg-type]
    assert len(world.events(Collision)) == 0  # nothing half-sent

    @system(reads=[Hit])
    def sends_without_declaring(world, dt):
        world.events(Hit).send(Hit(1, 1.0))

    @system()
    def reads_without_declaring(world, dt):
        world.events(Hit).read()

    for bad in (sends_without_declaring, reads_without_declaring):
        schedule = Schedule(("update",))
        schedule.add(bad)
        with pytest.raises(AccessError, match="Hit events"):
            schedule.run(world, 0.0)


def test_rows_sent_in_bulk_are_read_as_sent_and_must_match_the_fields():
    """send_rows (engine code's bulk path): the arrays are read back as they were given, after
    a checked send; an array of another dtype, shape or a missing field is refused and sends
    nothing."""
    world = World()
    channel = world.events(Collision)
    channel.send(Collision(a=1, b=2, impulse=(0.0, 1.0, 0.0)))
    rows = {"a": np.array([3, 4]), "b": np.array([5, 6]), "impulse": np.ones((2, 3), np.float32)}
    channel.send_rows(rows, 2)
    read = channel.read()
    assert read.a.tolist() == [1, 3, 4] and read.b.tolist() == [2, 5, 6]
    assert read.impulse.dtype == np.float32 and read.impulse[1:].tolist() == [[1.0] * 3] * 2
    for bad, what in (
        ({**rows, "impulse": np.ones((2, 3))}, "float64"),
        ({**rows, "a": np.array([3])}, r"\(1,\)"),
        ({"a": rows["a"], "b": rows["b"]}, "nothing"),
    ):
        with pytest.raises(TypeError, match=f"Collision.*{what}"):
            channel.send_rows(bad, 2)
    assert len(channel.read()) == 3
