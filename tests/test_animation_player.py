"""Clips played on entities (ecs_engine/animation/player.py): a glTF scene's clip plays on every
copy at each copy's own time and speed, loops or stops at its end, binds by the nodes' names so
one file's clip plays on another scene with the same names, and a clip handle the world lacks is
one error naming the entity."""

from __future__ import annotations

import numpy as np
import pytest
from gltf_files import GltfBuilder

from ecs_engine import World
from ecs_engine.animation import LINEAR, AnimationClips, Curve
from ecs_engine.animation.player import AnimationSystem
from ecs_engine.components import Name, Transform
from ecs_engine.components.animation import AnimationPlayer
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import Materials

KEYS = np.array([0.0, 1.0, 2.0])
SLIDE = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [3.0, 2.0, 0.0]])


def slide_at(t):
    return np.array([np.interp(t, KEYS, SLIDE[:, i]) for i in range(3)])


TURNS = np.array([[0.0, 0.0, 0.0, 1.0], [0.0, np.sin(0.6), 0.0, np.cos(0.6)], [0.0, 1.0, 0.0, 0.0]])
LIFT = np.array([[0.0, 5.0, 0.0], [0.0, 7.0, 0.0], [0.0, 5.0, 0.0]])


def arm_file(tmp_path, name="rig.gltf", extra_first=False):
    """A body with an arm below it; the clip 'wave' slides the arm (and 'still' holds the body),
    'lift' raises it and 'turn' turns it."""
    b = GltfBuilder()
    if extra_first:
        b.node("tail", translation=(0.0, -1.0, 0.0))  # node indices differ from the other file's
    arm = b.node("arm", translation=(0.5, 0.0, 0.0))
    body = b.node("body", children=[arm])
    b.animation([(arm, "translation", KEYS, SLIDE, LINEAR)], name="wave")
    b.animation([(body, "scale", [0.0], [[2.0, 2.0, 2.0]], LINEAR)], name="still")
    b.animation([(arm, "translation", KEYS, LIFT, LINEAR), (arm, "rotation", KEYS, TURNS, LINEAR)], name="lift")
    roots = [body] + ([0] if extra_first else [])
    b.scene(roots)
    return load_gltf(b.gltf(tmp_path / name), lambda mesh: 0, Materials())


def named(world, name):
    return sorted(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == name)


def step(world, seconds, dt=0.05):
    system = AnimationSystem()
    for _ in range(round(seconds / dt)):
        system.run(world, dt)


def test_each_copy_plays_at_its_own_time_and_speed(tmp_path):
    scene = arm_file(tmp_path)
    world = World()
    first = scene.spawn(world, play="wave")
    second = scene.spawn(world, Transform(position=(5.0, 0.0, 0.0)), play="wave")
    world.set(second, AnimationPlayer, time=0.5, speed=0.5)
    step(world, 0.6)
    arms = named(world, "arm")  # spawned in order: the first copy's first
    np.testing.assert_allclose(world.get(arms[0], Transform).position, slide_at(0.6), atol=1e-6)
    np.testing.assert_allclose(world.get(arms[1], Transform).position, slide_at(0.8), atol=1e-6)
    assert world.get(first, AnimationPlayer).time == pytest.approx(0.6)


def test_a_looping_clip_wraps_and_one_played_once_stops_at_its_end(tmp_path):
    scene = arm_file(tmp_path)
    world = World()
    looping = scene.spawn(world, play="wave")
    once = scene.spawn(world, play="wave")
    world.set(once, AnimationPlayer, looping=False)
    step(world, 2.5)
    arms = named(world, "arm")
    assert world.get(looping, AnimationPlayer).time == pytest.approx(0.5)
    np.testing.assert_allclose(world.get(arms[0], Transform).position, slide_at(0.5), atol=1e-6)
    assert world.get(once, AnimationPlayer).time == 2.0 and not world.get(once, AnimationPlayer).playing
    np.testing.assert_allclose(world.get(arms[1], Transform).position, SLIDE[-1], atol=1e-6)


def test_a_paused_or_clipless_player_leaves_its_targets_where_they_are(tmp_path):
    scene = arm_file(tmp_path)
    world = World()
    paused = scene.spawn(world, play="wave")
    world.set(paused, AnimationPlayer, playing=False, time=1.5)
    scene.spawn(world)  # a player with no clip
    step(world, 0.5)
    arms = named(world, "arm")
    np.testing.assert_allclose(world.get(arms[0], Transform).position, slide_at(1.5), atol=1e-6)  # posed, not moving
    np.testing.assert_allclose(world.get(arms[1], Transform).position, (0.5, 0.0, 0.0))  # its rest pose


def test_one_files_clip_plays_on_another_scene_with_the_same_names(tmp_path):
    source = arm_file(tmp_path, "source.gltf")
    other = arm_file(tmp_path, "other.gltf", extra_first=True)
    world = World()
    wave = source.clip_handles(world)["wave"]
    root = other.spawn(world)
    world.set(root, AnimationPlayer, clip=wave, playing=True)
    step(world, 1.5)
    (arm,) = named(world, "arm")
    np.testing.assert_allclose(world.get(arm, Transform).position, slide_at(1.5), atol=1e-6)
    (tail,) = named(world, "tail")
    np.testing.assert_allclose(world.get(tail, Transform).position, (0.0, -1.0, 0.0))  # not in the clip


def test_a_clip_the_world_lacks_or_a_scene_lacks_is_one_error(tmp_path):
    scene = arm_file(tmp_path)
    world = World()
    root = scene.spawn(world)
    world.set(root, AnimationPlayer, clip=7, playing=True)
    with pytest.raises(UsageError, match=rf"entity {root}: AnimationPlayer.clip is 7, but the world's AnimationClips"):
        step(world, 0.1)
    with pytest.raises(UsageError, match=r"rig.gltf: has no clip 'run' \(its clips: wave, still, lift\)"):
        scene.spawn(World(), play="run")
    assert len(world.resources[AnimationClips]) == 3


def test_a_crossfade_blends_the_old_clip_into_the_new_by_its_progress(tmp_path):
    from ecs_engine.animation.player import crossfade

    scene = arm_file(tmp_path)
    world = World()
    root = scene.spawn(world, play="wave")
    step(world, 0.4)
    crossfade(world, root, scene.clip_handles(world)["lift"], 0.5)
    step(world, 0.25)  # halfway: wave at 0.65 s, lift at 0.25 s, each weighing a half
    (arm,) = named(world, "arm")
    lift_at = np.array([np.interp(0.25, KEYS, LIFT[:, i]) for i in range(3)])
    np.testing.assert_allclose(world.get(arm, Transform).position, (slide_at(0.65) + lift_at) / 2, atol=1e-6)
    turn = Curve(KEYS, TURNS, LINEAR, rotation=True).sample(0.25)
    np.testing.assert_allclose(world.get(arm, Transform).rotation, turn, atol=1e-6)  # lift's alone: wave has no turn
    step(world, 0.3)  # the fade is over: lift alone, wave let go
    player = world.get(root, AnimationPlayer)
    assert player.from_clip == -1
    lift_at = np.array([np.interp(0.55, KEYS, LIFT[:, i]) for i in range(3)])
    np.testing.assert_allclose(world.get(arm, Transform).position, lift_at, atol=1e-6)


def test_a_crowd_s_clips_written_over_the_job_pool_equal_those_written_on_one_thread(tmp_path):
    """AnimationSystem hands its full-weight writes to the world's JobPool in pieces of rows
    (write_linear.write_all); a crowd of characters with different clips and times ends with the
    same Transforms, bit for bit, as without a pool, frame after frame."""
    from ecs_engine.demos.character import CLIPS, character_file
    from ecs_engine.jobs import JobPool
    from ecs_engine.render.assets.materials import materials

    def crowd(pool):
        world = World()
        scene = load_gltf(character_file(tmp_path), lambda mesh: 0, materials(world))
        n = 1400  # about 7 animated channels a character: 10k rows, several pieces of rows
        rng = np.random.default_rng(3)
        roots = scene.spawn_many(world, n, np.c_[np.arange(n) * 2.0, np.zeros(n), np.zeros(n)])
        handles = scene.clip_handles(world)
        clip = np.array([handles[name] for name in CLIPS], np.int32)[rng.integers(0, len(CLIPS), n)]
        world.set(roots, AnimationPlayer(clip=clip, time=rng.uniform(0, 1, n), speed=rng.uniform(0.8, 1.2, n)))
        if pool is not None:
            world.resources[JobPool] = pool
        system = AnimationSystem()
        out = []
        for _ in range(3):
            world.run_system(system, 0.05)
            out.append(np.concatenate([b[Transform].rotation.copy() for b in world.query(Transform)]))
        return out

    with JobPool(4) as pool:
        spread = crowd(pool)
    alone = crowd(None)
    assert len(spread[0]) > 30000
    for a, b in zip(spread, alone, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(spread[0], spread[2])  # the clips move
