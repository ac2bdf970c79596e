"""Frame extraction needs no GPU: what a frame will draw (chunks, lights, camera, planes) comes
from the world alone, and is kept between frames exactly while the world does not change it."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, PointLight, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.extract.frame_data import MIN_CHUNK_ROWS, FrameExtractor


def scene(n: int = 50) -> World:
    world = World()
    world.spawn_batch(n, Transform(position=np.c_[np.arange(n) - n / 2, np.zeros((n, 2))]), Mesh(handle=0))
    world.spawn_batch(3, Transform(position=(0.0, 5.0, 0.0)), Mesh(handle=1, material=2))
    world.spawn(Transform(position=(1.0, 2.0, 3.0)), PointLight(intensity=2.0))
    add_camera(world, eye=(0.0, 1.0, 10.0), target=(0.0, 0.0, 0.0))
    default_schedule().run(world, 0.0)
    return world


def test_extraction_reads_chunks_lights_and_camera_from_the_world():
    world = scene()
    data = FrameExtractor(lambda: 1, chunk_rows=16).extract(world, 4 / 3, mesh_count=2, culling="frustum")
    # one table (Transform, Mesh, ModelMatrix): jobs of 16 rows, the last one shorter
    assert data.candidates == 53 and [len(c.handle) for c in data.chunks] == [16, 16, 16, 5]
    assert [c.offset for c in data.chunks] == [0, 16, 32, 48]  # each chunk's slice of the buffer
    assert data.chunks[-1].handle.tolist() == [0, 0, 1, 1, 1] and data.chunks[-1].material.tolist() == [0, 0, 2, 2, 2]
    assert data.light_count == 1 and data.lights[0].intensity.tolist() == [2.0]
    assert data.camera.position.tolist() == [0.0, 1.0, 10.0]
    assert np.allclose(data.origin, data.camera.position)  # camera-relative by default
    assert data.planes.shape == (5, 4)  # infinite far plane: five planes
    assert FrameExtractor(lambda: 1).extract(world, 4 / 3, 2, culling="none").planes is None


def test_what_is_kept_is_the_same_object_until_the_world_changes_it():
    world = scene()
    ex = FrameExtractor(lambda: 2)
    first = ex.extract(world, 1.5, 2, True)
    again = ex.extract(world, 1.5, 2, True)
    assert again.chunks is first.chunks and again.view is first.view and again.planes is first.planes
    world.spawn(Transform(), Mesh(handle=1))
    assert ex.extract(world, 1.5, 2, True).candidates == 54  # a new row: the chunks are rebuilt
    wider = ex.extract(world, 2.0, 2, True)
    assert wider.view is not first.view and not np.allclose(wider.planes, first.planes)


def test_a_mesh_handle_beyond_the_uploaded_meshes_is_named():
    world = scene()
    with pytest.raises(ValueError, match=r"Mesh\.handle 1 does not name an uploaded mesh"):
        FrameExtractor(lambda: 1).extract(world, 1.0, mesh_count=1, culling="frustum")


def test_jobs_follow_the_thread_count_but_never_get_tiny():
    threads = [1]
    ex = FrameExtractor(lambda: threads[0])
    assert ex.rows_per_job(1_000_000) == 1_000_000
    threads[0] = 16
    assert ex.rows_per_job(1_000_000) == 62_500 and ex.rows_per_job(100_000) == MIN_CHUNK_ROWS
