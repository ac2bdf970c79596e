"""Layers (animation/layers.py): a layer's clip blends over the player's by its weight, only on
the targets its mask names, on its own clock; masks come from a scene's subtree by path; a bad
mask or clip is one error."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.animation import LINEAR, AnimationClip, AnimationClips, ClipChannel, Curve, target_id
from ecs_engine.animation.layers import AnimationLayerSystem, AnimationMasks, targets_below
from ecs_engine.animation.player import AnimationSystem
from ecs_engine.components import Transform
from ecs_engine.components.animation import AnimationLayers, AnimationPlayer, AnimationTarget
from ecs_engine.errors import UsageError

PATHS = ["hips", "hips/legs", "hips/chest", "hips/chest/arm"]


def _quat(angle):
    return np.array([0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)])


def _clip(name, angle, x):
    """Every path turned by `angle` about z and moved to x, held over two seconds."""
    turn = Curve(np.array([0.0, 2.0]), np.stack([_quat(angle)] * 2), LINEAR, rotation=True)
    move = Curve(np.array([0.0, 2.0]), np.array([[x, 0.0, 0.0]] * 2), LINEAR)
    channels = [
        ClipChannel(target_id(p), prop, c) for p in PATHS for prop, c in (("rotation", turn), ("translation", move))
    ]
    return AnimationClip(name, tuple(channels))


def _world(**layers):
    world = World()
    clips = world.resources.setdefault(AnimationClips, AnimationClips())
    walk, wave = clips.add(_clip("walk", 0.0, 0.0)), clips.add(_clip("wave", 1.2, 2.0))
    masks = world.resources.setdefault(AnimationMasks, AnimationMasks())
    upper = masks.add(targets_below(PATHS, "hips/chest"))
    fields = {"clip": (wave, -1), "mask": (upper, -1), **layers}
    root = world.spawn(Transform(), AnimationPlayer(clip=walk), AnimationLayers(**fields))
    parts = {p: world.spawn(Transform(), AnimationTarget(player=root, id=target_id(p))) for p in PATHS}
    return world, root, parts


def _run(world, dt=0.1):
    for system in (AnimationSystem(), AnimationLayerSystem()):
        world.run_system(system, dt)


def test_a_layer_moves_only_its_mask_s_targets_by_its_weight():
    world, _, parts = _world()
    _run(world)
    x = {p: float(world.get(e, Transform).position[0]) for p, e in parts.items()}
    assert x == {"hips": 0.0, "hips/legs": 0.0, "hips/chest": 2.0, "hips/chest/arm": 2.0}
    assert np.allclose(world.get(parts["hips/chest/arm"], Transform).rotation, _quat(1.2))
    world, _, parts = _world(weight=(0.25, 1.0), mask=(-1, -1))  # every target, a quarter
    _run(world)
    for e in parts.values():
        t = world.get(e, Transform)
        assert np.isclose(t.position[0], 0.5) and np.allclose(t.rotation, _quat(0.3), atol=1e-9)  # slerp: a quarter


def test_a_layer_keeps_its_own_clock_and_stops_at_a_one_shot_end():
    world, root, _ = _world(looping=(False, True), speed=(2.0, 1.0))
    for _ in range(4):
        _run(world, 0.3)
    layers = world.get(root, AnimationLayers)
    assert np.isclose(layers.time[0], 2.0) and not layers.playing[0]  # 2.4 s of a 2 s clip: held at its end
    assert np.isclose(world.get(root, AnimationPlayer).time, 1.2)  # the player's clock: its own


def test_bad_masks_and_clips_are_one_error():
    with pytest.raises(UsageError, match="no node at or under"):
        targets_below(PATHS, "tail")
    with pytest.raises(UsageError, match="at least one target"):
        AnimationMasks().add([])
    world, _, _ = _world(mask=(7, -1))
    with pytest.raises(UsageError, match="no animation mask 7"):
        _run(world)
    world, _, _ = _world(clip=(9, -1))
    with pytest.raises(UsageError, match=r"AnimationLayers\.clip names clip 9"):
        _run(world)


def test_a_layer_blends_morph_weights_by_its_weight_and_mask_and_the_parts_follow():
    """A layer's weights channel blends over the player's morph weights as positions do
    (linearly, by the layer's weight), only on its mask's targets; a node's parts (children with
    MorphWeights and no target) take the blended weights."""
    from ecs_engine.components import Parent
    from ecs_engine.components.animation import MorphWeights

    def held(values):
        return Curve(np.array([0.0, 2.0]), np.array([values, values], np.float64), LINEAR)

    world = World()
    clips = world.resources.setdefault(AnimationClips, AnimationClips())
    base = clips.add(AnimationClip("base", (ClipChannel(target_id("face"), "weights", held([0.2, 0.0])),)))
    over = clips.add(AnimationClip("over", (ClipChannel(target_id("face"), "weights", held([1.0, 0.6])),)))
    masks = world.resources.setdefault(AnimationMasks, AnimationMasks())
    elsewhere = masks.add([target_id("hips")])
    root = world.spawn(Transform(), AnimationPlayer(clip=base), AnimationLayers(clip=(over, over), weight=(0.25, 0.0)))
    face = world.spawn(Transform(), AnimationTarget(player=root, id=target_id("face")), MorphWeights())
    part = world.spawn(Transform(), Parent(entity=face), MorphWeights())
    _run(world)
    want = [0.2 + 0.8 * 0.25, 0.6 * 0.25]
    np.testing.assert_allclose(world.get(face, MorphWeights).weights[:2], want, atol=1e-6)
    np.testing.assert_allclose(world.get(part, MorphWeights).weights[:2], want, atol=1e-6)
    assert not world.get(face, MorphWeights).weights[2:].any()
    world.set(root, AnimationLayers, mask=(elsewhere, -1))  # the face is not in the mask
    _run(world)
    np.testing.assert_allclose(world.get(face, MorphWeights).weights[:2], [0.2, 0.0], atol=1e-6)
