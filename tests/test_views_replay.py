"""Frame replay with more camera views than frame slots (render/frame/view_frames.py): each view
keeps its own recording per slot, so a still split screen of 3 or 4 views over 2 slots submits
its frames again; a moving object is drawn where it is (no view replays a stale frame, nor
another view's rows)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform, Viewport
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh

W, H = 48, 32
XS = (-20.0, 0.0, 20.0, 40.0)  # the cubes' x: far apart, one camera over each


def _world(mesh: int, views: int) -> tuple[World, list[int]]:
    """A cube per view, each of its own colour, and a camera over each in a strip of the window."""
    world = World()
    cubes = []
    for i, x in enumerate(XS[:views]):
        color = [(1.0, 0.0, 0.0, 1.0), (0.0, 1.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0), (1.0, 1.0, 0.0, 1.0)][i]
        material = materials(world).add(Material(f"m{i}", "lambert", color))
        place = Transform(position=(x, 0.0, 0.0), scale=(1.5, 1.5, 1.5))
        cubes.append(int(world.spawn(place, Mesh(handle=mesh, material=material))))
        strip = Viewport(x=i / views, width=1.0 / views)
        world.spawn(Transform(position=(x, 0.0, 4.0)), Camera(fov_y=math.radians(60.0)), strip)
    world.spawn(Transform(), DirectionalLight(illuminance=3.0))
    return world, cubes


def _fresh(gpu, world: World) -> np.ndarray:
    """The world's picture from a renderer of its own (nothing recorded before)."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].astype(np.int64)
    finally:
        renderer.destroy()


@pytest.mark.parametrize("views", [3, 4])
def test_more_views_than_slots_replay_a_still_scene_and_redraw_a_moving_one(views: int) -> None:
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        world, cubes = _world(mesh, views)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        schedule = default_schedule()
        try:
            assert len(renderer.frames.frames) < views
            schedule.run(world, 0.0)
            for _ in range(3):  # every view has recorded in every slot
                renderer.render(world, readback=True)
            replayed = renderer.replay.replayed
            for _ in range(4):
                renderer.render(world, readback=True)
            assert renderer.replay.replayed - replayed == 4 * views  # every view-frame submitted again
            still = gpu.target.pixels()[..., :3].astype(np.int64)
            # the second cube moves up in its view: its view draws it there, every frame after
            moved = []
            for step in range(3):
                world.set(cubes[1], Transform(position=(XS[1], 0.3 * (step + 1), 0.0), scale=(1.5, 1.5, 1.5)))
                schedule.run(world, 0.0)
                renderer.render(world, readback=True)
                moved.append(gpu.target.pixels()[..., :3].astype(np.int64))
            replayed = renderer.replay.replayed
            for _ in range(3):  # still again: every view replays once it has recorded in each slot
                renderer.render(world, readback=True)
            again = gpu.target.pixels()[..., :3].astype(np.int64)
        finally:
            renderer.destroy()
        expected = _fresh(gpu, world)
    assert renderer.replay.replayed - replayed >= views
    assert np.array_equal(again, expected)
    assert np.array_equal(moved[-1], expected)
    assert not np.array_equal(moved[0], still) and not np.array_equal(moved[1], moved[0])


def test_view_recordings_go_with_their_views() -> None:
    """A view taken away frees its command buffers in every slot; the ones left still replay."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        world, _ = _world(mesh, 4)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        schedule = default_schedule()
        try:
            schedule.run(world, 0.0)
            for _ in range(3):
                renderer.render(world)
            assert len(renderer.views.recordings.views) == 4
            last = [int(e) for e in world.query(Camera, write=()).entities()][-1]
            world.destroy(last)
            schedule.run(world, 0.0)
            for _ in range(3):
                renderer.render(world)
            assert len(renderer.views.recordings.views) == 3
            replayed = renderer.replay.replayed
            renderer.render(world)
            assert renderer.replay.replayed - replayed == 3
        finally:
            renderer.destroy()


def test_a_resized_worker_pool_takes_the_views_pools_of_its_old_threads() -> None:
    """The worker threads replaced: the secondaries' pools the views keep for threads that are
    gone are destroyed (as the slots' own are), and the views draw as before."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.gpu.secondary import _ThreadPool
    from ecs_engine.jobs import JobPool
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu, JobPool(2) as pool:
        mesh = gpu.meshes.add(cube_mesh())
        world, _ = _world(mesh, 3)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, jobs=pool)
        schedule = default_schedule()
        try:
            schedule.run(world, 0.0)
            for _ in range(3):
                renderer.render(world)
            recs = [rec for slots in renderer.views.recordings.views.values() for rec in slots if rec is not None]
            assert len(recs) == 6  # 3 views in 2 slots
            recs[0].secondaries[-1] = _ThreadPool(gpu.device)  # a thread's that is gone (no ident is -1)
            for _ in range(2):
                renderer.render(world)
            assert -1 in recs[0].secondaries  # the same threads: nothing goes
            pool.resize(3)
            for _ in range(3):
                renderer.render(world, readback=True)
            assert all(-1 not in rec.secondaries for rec in recs)
            picture = gpu.target.pixels()[..., :3].astype(np.int64)
        finally:
            renderer.destroy()
        expected = _fresh(gpu, world)
    assert np.array_equal(picture, expected)
