"""The animation demo (demos/animation.py): its characters stroll, and each plays the clip of its
gait band (idle, walk, run), reached by a cross-fade when the band changes; the scene's systems
join the demo schedule (scenes.scene_systems), and a frame of it draws."""

from __future__ import annotations

import numpy as np
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule, scene_builder, scene_systems
from ecs_engine.components import Transform
from ecs_engine.components.animation import AnimationPlayer


def _demo(n, add_mesh):
    from ecs_engine.demos.animation import CrowdClips, Stroll

    world = World()
    scene_builder("animation", entities=n)(world, add_mesh)
    schedule = default_schedule()
    for stage, system in scene_systems("animation"):
        schedule.add(system, stage)
    return world, schedule, Stroll, world.resources[CrowdClips].handles


def _columns(world, Stroll):
    (batch,) = list(world.query(Stroll, Transform, AnimationPlayer, write=()))
    s, t, p = batch[Stroll], batch[Transform], batch[AnimationPlayer]
    return s.band.copy(), s.speed.copy(), t.position.copy(), p.clip.copy(), p.from_clip.copy()


def test_characters_stroll_and_cross_fade_to_the_clip_of_their_gait(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    meshes = []
    world, schedule, Stroll, handles = _demo(30, lambda m: meshes.append(m) or len(meshes) - 1)
    start = _columns(world, Stroll)[2]
    fades, bands = 0, set()
    for _ in range(240):  # eight seconds
        schedule.run(world, 1 / 30)
        band, speed, _, clip, from_clip = _columns(world, Stroll)
        fades += int((from_clip >= 0).sum())
        bands |= set(band.tolist())
        settled = from_clip < 0
        assert (clip[settled] == np.array(handles)[band[settled]]).all()  # each plays its band's clip
        assert ((speed < 0.35) == (band == 0)).all()
    moved = np.linalg.norm(_columns(world, Stroll)[2] - start, axis=1)
    assert bands == {0, 1, 2} and fades > 0 and (moved > 1.0).sum() > 10


def test_a_frame_of_the_demo_draws_its_characters(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    with headless_gpu(96, 64) as gpu:
        world, schedule, _, _ = _demo(4, gpu.meshes.add)
        for _ in range(3):
            schedule.run(world, 1 / 30)
        img = render_world(gpu, world)
    skin = (img[..., 0] > img[..., 2] + 25) & (img[..., 0] > 60)  # the characters' warm colour
    assert skin.sum() > 20, skin.sum()
