"""Marks on clips (AnimationClips.mark) sent as AnimationEvents when a player's time passes them:
once per pass, in order, round the loop's end, backwards too, at a one-shot clip's end, never
from a paused player; a bad mark is one error."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.animation import LINEAR, AnimationClip, AnimationClips, ClipChannel, Curve, target_id
from ecs_engine.animation.player import AnimationSystem
from ecs_engine.components import Transform
from ecs_engine.components.animation import AnimationEvent, AnimationPlayer, AnimationTarget
from ecs_engine.errors import UsageError


def _world(**player):
    world = World()
    clips = world.resources.setdefault(AnimationClips, AnimationClips())
    slide = Curve(np.array([0.0, 1.0]), np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), LINEAR)
    walk = clips.add(AnimationClip("walk", (ClipChannel(target_id("legs"), "translation", slide),)))
    clips.mark(walk, 0.75, "step.R")
    clips.mark(walk, 0.25, "step.L")
    root = world.spawn(Transform(), AnimationPlayer(clip=walk, **player))
    world.spawn(Transform(), AnimationTarget(player=root, id=target_id("legs")))
    return world, root


def _run(world, frames, dt=0.1):
    """(name, time, player) of every event heard over `frames` frames, read each frame."""
    from ecs_engine.ecs.events import Reader

    system, reader, heard = AnimationSystem(), Reader(0), []
    for _ in range(frames):
        world.run_system(system, dt)
        got = world.events(AnimationEvent).read(reader)
        heard += [(str(n), round(float(t), 3), int(p)) for n, t, p in zip(got.name, got.time, got.player, strict=True)]
        world.update_events()
    return heard


def test_marks_are_heard_once_per_pass_in_order_and_round_the_loop():
    world, root = _world()
    heard = _run(world, 25)  # 2.5 s of a 1 s clip
    assert [(n, t) for n, t, _ in heard] == [("step.L", 0.25), ("step.R", 0.75)] * 2 + [("step.L", 0.25)]
    assert {p for _, _, p in heard} == {root}


def test_backwards_a_stopped_player_and_a_one_shot_end():
    world, _ = _world(speed=-1.0, time=0.9)
    assert [n for n, _, _ in _run(world, 10)] == ["step.R", "step.L"]  # 0.9 down to 0.0... and round
    world, _ = _world(playing=False)
    assert _run(world, 20) == []
    world, root = _world(looping=False)
    world.resources[AnimationClips].mark(0, 1.0, "done")
    heard = _run(world, 20)
    assert [n for n, _, _ in heard] == ["step.L", "step.R", "done"]  # the end's mark once, then stopped
    assert not bool(world.get(root, AnimationPlayer).playing)


def test_a_bad_mark_is_one_error():
    world, _ = _world()
    clips = world.resources[AnimationClips]
    with pytest.raises(UsageError, match="within 0 to 1"):
        clips.mark(0, 1.5, "late")
    with pytest.raises(UsageError, match="1 to 32 characters"):
        clips.mark(0, 0.5, "x" * 40)
