"""Two-phase occlusion culling (render/culling/occlusion_passes.py): the image equals frustum culling's, frame
after frame while things move, with far fewer rows drawn in a dense scene; the pyramid's levels;
sub-pixel rows culled; refusals and fallbacks."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, Transform
from ecs_engine.demos import scaling
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.culling.occlusion_passes import pyramid_levels
from ecs_engine.render.frame.renderer import Renderer

W, H = 96, 64


def scaling_world(gpu, entities: int) -> World:
    world = World()
    scaling.build(world, gpu.meshes.add, entities=entities)
    return world


def frames(gpu, world: World, culling: str, count: int, **kw):
    """Per frame after a schedule step: (pixels, rows drawn)."""
    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect", culling=culling, lod=False, **kw)
    schedule = default_schedule()
    out = []
    try:
        for _ in range(count):
            schedule.run(world, 1 / 30)
            stats = renderer.render(world, readback=True)
            out.append((gpu.target.pixels()[..., :3].copy(), stats.instances))
    finally:
        renderer.destroy()
    return out


def test_images_equal_frustum_culling_while_everything_moves_and_fewer_rows_are_drawn():
    with headless_gpu(W, H) as gpu:
        saved = scaling_world(gpu, 4000)
        world = scaling_world(gpu, 4000)
        frustum = frames(gpu, saved, "frustum", 4)
        occluded = frames(gpu, world, "occlusion", 4)
    for (a, drawn_all), (b, drawn) in zip(frustum, occluded, strict=True):
        assert a[..., :3].max() > 30
        assert np.array_equal(a, b)
        assert drawn <= drawn_all
    # from the second frame on the early pass has last frame's set: what it hides is not drawn
    assert all(drawn < 0.8 * drawn_all for (_, drawn_all), (_, drawn) in zip(frustum[1:], occluded[1:], strict=True))


def tiny_and_one_big_cube(gpu) -> World:
    """One cube filling the middle, and 200 cubes far smaller than a pixel beside it."""
    world = World()
    cube = gpu.meshes.add(cube_mesh())
    rng = np.random.default_rng(3)
    far = np.column_stack([rng.uniform(-9, 9, 200), rng.uniform(-6, 6, 200), np.full(200, -10.0)])
    world.spawn_batch(200, Transform(position=far, scale=(0.001, 0.001, 0.001)), Mesh(handle=cube))
    world.spawn(Transform(position=(0.0, 0.0, 0.0)), Mesh(handle=cube))
    add_camera(world, eye=(0.0, 0.0, 6.0), target=(0.0, 0.0, 0.0))
    return world


def test_rows_that_cover_no_pixel_centre_are_not_drawn_and_the_image_is_unchanged():
    with headless_gpu(W, H) as gpu:
        frustum = frames(gpu, tiny_and_one_big_cube(gpu), "frustum", 2)
        occluded = frames(gpu, tiny_and_one_big_cube(gpu), "occlusion", 2)
    assert [n for _, n in frustum] == [201, 201]
    # a tiny cube within 1/16 pixel of a pixel centre is kept (the rasteriser's snapping margin):
    # about 3 of the 200 by chance
    assert all(1 <= n <= 15 for _, n in occluded), [n for _, n in occluded]
    assert all(np.array_equal(a, b) for (a, _), (b, _) in zip(frustum, occluded, strict=True))


def test_with_msaa_the_image_still_equals_frustum_cullings():
    """The early depth takes the target's samples, the pyramid the farthest of them."""
    from ecs_engine.gpu.offscreen import OffscreenTarget

    out = {}
    with headless_gpu(W, H) as gpu:
        target = OffscreenTarget(gpu.device, W, H, samples=4)
        gpu.owned.append(target)
        for culling in ("frustum", "occlusion"):
            world = scaling_world(gpu, 4000)
            renderer = Renderer(gpu.device, target, gpu.meshes, mode="indirect", culling=culling, lod=False)
            gpu.owned.append(renderer)
            schedule = default_schedule()
            out[culling] = []
            for _ in range(3):
                schedule.run(world, 1 / 30)
                drawn = renderer.render(world, readback=True).instances
                out[culling].append((target.pixels()[..., :3].copy(), drawn))
        assert renderer.path.occlusion is not None and renderer.path.occlusion.samples == 4
    for (a, drawn_all), (b, drawn) in zip(out["frustum"], out["occlusion"], strict=True):
        assert np.array_equal(a, b)
        assert drawn <= drawn_all
    assert out["occlusion"][-1][1] < 0.95 * out["frustum"][-1][1]  # hidden rows culled (no sub-pixel culling)


def test_wireframe_frames_cull_the_frustum_alone():
    with headless_gpu(W, H) as gpu:
        world = tiny_and_one_big_cube(gpu)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect", culling="occlusion", fill="wireframe")
        gpu.owned.append(renderer)
        default_schedule().run(world, 0.0)
        counts = [renderer.render(world, readback=True).instances for _ in range(2)]
        assert counts == [201, 201]  # the tiny cubes too: no sub-pixel culling either
        assert renderer.path.occlusion is None  # never made


def test_pyramid_levels_halve_rounding_up_to_one_texel():
    levels = pyramid_levels(1280, 720)
    assert [(w, h) for _, w, h in levels[:3]] == [(640, 360), (320, 180), (160, 90)]
    assert levels[-1][1:] == (1, 1) and len(levels) == 11
    firsts = [f for f, _, _ in levels]
    assert firsts == [0] + list(np.cumsum([w * h for _, w, h in levels[:-1]]))
    assert [(w, h) for _, w, h in pyramid_levels(5, 3)] == [(3, 2), (2, 1), (1, 1)]
    assert [(w, h) for _, w, h in pyramid_levels(1, 1)] == [(1, 1)]


def test_occlusion_culling_outside_the_indirect_mode_is_one_clear_refusal():
    with headless_gpu(W, H) as gpu, pytest.raises(UsageError, match="--culling occlusion needs --mode indirect"):
        Renderer(gpu.device, gpu.target, gpu.meshes, mode="instanced", culling="occlusion")


def test_with_levels_of_detail_and_mirrored_rows_the_early_pass_reads_the_scenes_command_lists(monkeypatch):
    """The early depth pass draws from the same per-winding lists as the scene (compact writes
    them a draw-mesh count apart), and the image still equals frustum culling's."""
    import ecs_engine.render.draw.indirect_path as indirect

    lists = []
    real = indirect.record_indirect_draws

    def spy(vk, cb, pipelines, merged, key_counts, commands, state, offsets):
        lists.append(len(key_counts))
        return real(vk, cb, pipelines, merged, key_counts, commands, state, offsets)

    monkeypatch.setattr(indirect, "record_indirect_draws", spy)
    images = {}
    with headless_gpu(W, H) as gpu:
        for culling in ("frustum", "occlusion"):
            world = scaling_world(gpu, 3000)
            for batch in world.query(Transform):
                scale = batch[Transform].scale
                scale[::3, 0] *= -1.0  # a third of the rows mirrored
            renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect", culling=culling)
            gpu.owned.append(renderer)
            schedule = default_schedule()
            images[culling] = []
            for _ in range(3):
                schedule.run(world, 1 / 30)
                renderer.render(world, readback=True)
                images[culling].append(gpu.target.pixels()[..., :3].copy())
        merged = gpu.meshes.merged()
        assert merged.draw_meshes > merged.count  # the knot has levels of detail
    assert set(lists) == {2 * merged.draw_meshes}  # early and scene draws alike
    assert all(np.array_equal(a, b) for a, b in zip(images["frustum"], images["occlusion"], strict=True))
