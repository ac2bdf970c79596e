"""The render system's chunk jobs: every mode, thread count and culling setting draws the same
image; culling drops what is off screen; a failing job is reported and the next frame renders."""

from __future__ import annotations

import numpy as np
import pytest
from golden_images import SIZE, assert_close_to_golden, image_difference
from gpu_context import headless_gpu

from ecs_engine.app.loop import run
from ecs_engine.app.settings import RunOptions
from ecs_engine.jobs import JobError


def grid(tmp_path, **kw):
    result = run(
        RunOptions(
            scene="grid100",
            width=SIZE[0],
            height=SIZE[1],
            frames=8,
            validate=True,
            quiet=True,
            screenshot=str(tmp_path / "g.png"),
            **kw,
        )
    )
    assert result.validation_messages == []
    return result


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return grid(tmp_path_factory.mktemp("ref"), mode="instanced", threads=1, recorder="python").pixels


@pytest.mark.parametrize("recorder", ["python", "native"])
@pytest.mark.parametrize(
    "mode, threads, culling",
    [
        ("instanced", 1, "frustum"),
        ("instanced", 2, "frustum"),
        ("instanced", 4, "frustum"),
        ("instanced", 2, "temporal"),
        ("per_entity", 1, "frustum"),
        ("per_entity", 2, "frustum"),
        ("per_entity", 2, "temporal"),
        ("per_entity", 4, "none"),
        ("instanced", 1, "none"),
        ("indirect", 1, "frustum"),
        ("indirect", 2, "frustum"),
        ("indirect", 4, "none"),
    ],
)
def test_same_image_in_every_mode_recorder_and_thread_count(reference, tmp_path, mode, threads, culling, recorder):
    if recorder == "native":
        pytest.importorskip("numba")
    # chunks of 16 rows: several jobs even for 100 cubes
    result = grid(tmp_path, mode=mode, threads=threads, culling=culling, chunk_rows=16, recorder=recorder)
    mean, outliers = image_difference(result.pixels, reference)
    assert mean < 0.05 and outliers == 0  # the same picture, not just a similar one
    assert_close_to_golden(result.pixels, "grid100")
    stats = result.last_stats
    assert stats.chunks == 7 and stats.candidates == 100
    # per_entity: one per cube; instanced: one per chunk; indirect: one command for the one
    # mesh (counted on the GPU); each plus the light billboards
    assert stats.draws == 1 + {"per_entity": stats.instances, "instanced": stats.chunks, "indirect": 1}[mode]
    assert stats.instances == 100


@pytest.mark.parametrize(
    "mode, culling", [("instanced", "frustum"), ("instanced", "temporal"), ("indirect", "frustum")]
)
def test_culling_drops_what_is_off_screen(tmp_path, monkeypatch, mode, culling):
    import ecs_engine.demos.grid100 as grid100

    original = grid100.build

    def build(world, add_mesh, path=None):
        original(world, add_mesh, path)
        from ecs_engine.components import Mesh, Transform

        # 50 cubes behind the camera: culled, and the picture does not change
        world.spawn_batch(
            50, Transform(position=np.tile([20.0, 10.0, 30.0], (50, 1)) + np.arange(50)[:, None]), Mesh(handle=0)
        )

    monkeypatch.setattr(grid100, "build", build)
    culled = grid(tmp_path, threads=2, mode=mode, culling=culling)
    assert culled.last_stats.candidates == 150 and culled.last_stats.instances == 100
    assert_close_to_golden(culled.pixels, "grid100")
    everything = grid(tmp_path, threads=2, culling="none", mode=mode)
    assert everything.last_stats.instances == 150


def test_a_failing_job_names_its_chunk_and_the_next_frame_renders(monkeypatch):
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.demos import grid100
    from ecs_engine.ecs.world import World
    from ecs_engine.jobs import JobPool
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu() as gpu:
        jobs = JobPool(3)
        gpu.owned.append(jobs)
        world = World()
        grid100.build(world, gpu.meshes.add)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, jobs=jobs, chunk_rows=20)
        gpu.owned.append(renderer)
        real = renderer.path.record_chunk

        def flaky(chunk, ctx):
            if chunk.offset == 40:
                raise RuntimeError("boom")
            return real(chunk, ctx)

        default_schedule().run(world, 0.0)
        monkeypatch.setattr(renderer.path, "record_chunk", flaky)
        with pytest.raises(JobError, match=r"chunk rows 40:60 failed: RuntimeError: boom"):
            renderer.render(world)
        monkeypatch.setattr(renderer.path, "record_chunk", real)
        stats = renderer.render(world, readback=True)
        assert stats.instances > 0 and gpu.target.pixels()[..., :3].max() > 30
        stats = renderer.render(world, readback=True)
        assert stats.gpu_ms is None or stats.gpu_ms > 0


def test_jobs_are_about_one_per_thread_but_never_tiny():
    from ecs_engine.render.extract.frame_data import MIN_CHUNK_ROWS, FrameExtractor

    def rows(n, threads, chunk_rows=None):
        return FrameExtractor(lambda: threads, chunk_rows).rows_per_job(n)

    assert rows(1_000_000, 16) == 62_500  # 16 jobs
    assert rows(100_000, 16) == MIN_CHUNK_ROWS  # 7 jobs, not 16 of 6,250 rows
    assert rows(100, 1) == MIN_CHUNK_ROWS and rows(100, 4, chunk_rows=16) == 16
