"""Rendering on lavapipe with the validation layers on: every message is a failure.

Golden images: each seed scene rendered headless at 160x120 after 8 fixed steps, compared with
tests/golden/<scene>.png. Tolerance (documented in tests/golden/README.md): mean absolute
difference <= 1.5 (of 255) and at most 0.5% of pixels off by more than 24 in any channel,
which absorbs rasteriser rounding between Mesa versions but not a moved object, a lost light
or a wrong winding. ECS_ENGINE_UPDATE_GOLDEN=1 rewrites the references.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from golden_images import GOLDEN, SIZE, assert_close_to_golden, image_difference
from gpu_context import headless_gpu
from PIL import Image

from ecs_engine import World
from ecs_engine.app.loop import run
from ecs_engine.app.scenes import default_schedule
from ecs_engine.app.settings import RunOptions
from ecs_engine.components import Camera, Mesh, PointLight, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.assets.primitives import cube_mesh


def render(scene: str, frames: int = 8, **kw) -> object:
    result = run(
        RunOptions(
            scene=scene,
            width=SIZE[0],
            height=SIZE[1],
            frames=frames,
            screenshot=kw.pop("screenshot", None),
            validate=True,
            quiet=True,
            anisotropy=1,  # a textured scene's image the same on every driver (test_texture_filtering.py)
            **kw,
        )
    )
    assert result.validation_messages == []
    return result


@pytest.mark.parametrize("scene", ["cube", "grid100", "model"])
def test_seed_scenes_match_golden_images(scene, tmp_path):
    shot = tmp_path / f"{scene}.png"
    result = render(scene, screenshot=str(shot))
    assert shot.is_file()
    assert_close_to_golden(result.pixels, scene)
    stats = result.last_stats
    assert stats.lights == 6
    assert stats.instances == {"cube": 1, "grid100": 100, "model": 1}[scene]
    assert stats.draws == 2  # one instanced draw of the shared mesh, one for the billboards


@pytest.mark.parametrize(
    "scene, lights, instances, options",
    [
        ("materials", 3, 37, {}),
        ("lights", 257, None, {"lights": 256}),  # clustered
        ("shadows", 3, 5, {}),
        ("environment", 1, 6, {}),  # its generated sky, mirrored, refracted and lighting the ambient
        ("split_screen", 6, None, {}),  # three cameras' views: two halves and an inset (render/frame/views.py)
        ("monitor", 2, None, {}),  # a screen showing a second camera's picture (render/frame/texture_views.py)
    ],
)
def test_demo_scenes_match_golden_images(scene, lights, instances, options, tmp_path):
    result = render(scene, screenshot=str(tmp_path / f"{scene}.png"), **options)
    assert_close_to_golden(result.pixels, scene)
    assert result.last_stats.lights == lights
    assert instances is None or result.last_stats.instances == instances


def test_golden_comparison_detects_a_changed_scene():
    """The tolerance is not so loose that a different picture passes."""
    cube = np.asarray(Image.open(GOLDEN / "cube.png").convert("RGB"))
    grid = np.asarray(Image.open(GOLDEN / "grid100.png").convert("RGB"))
    shifted = np.roll(cube, 6, axis=1)
    for other in (grid, shifted):
        mean, outliers = image_difference(other, cube)
        assert mean > 1.5 or outliers > 0.005


def test_gpu_timestamps_and_wall_clock():
    result = render("grid100", frames=6)
    assert len(result.gpu_ms) >= 4 and min(result.gpu_ms) > 0.0
    assert result.fps == pytest.approx(result.frames / result.wall_s)


def build_cubes(scales):
    def build(world: World, add_mesh, path=None) -> None:
        cube = add_mesh(cube_mesh())
        for i, s in enumerate(scales):
            world.spawn(Transform(position=(1.2 * (i - (len(scales) - 1) / 2), 0.0, 0.0), scale=s), Mesh(handle=cube))
        add_camera(world, eye=(0.4, 0.9, 3.0), target=(0.0, 0.0, 0.0))
        # a light, so faces are shaded by their normals: a cube drawn inside out (wrong winding)
        # has the same silhouette as the right one and differs only there
        world.spawn(Transform(position=(1.5, 2.5, 2.5)), PointLight(color=(1.0, 1.0, 1.0), intensity=6.0))

    return build


def render_custom(build, monkeypatch, tmp_path, mode: str = "instanced") -> np.ndarray:
    import ecs_engine.app.session as session

    monkeypatch.setattr(session, "scene_builder", lambda name, entities=None, lights=None, shadows=True: build)
    result = run(
        RunOptions(
            scene="cube",
            width=SIZE[0],
            height=SIZE[1],
            frames=1,
            screenshot=str(tmp_path / "x.png"),
            validate=True,
            quiet=True,
            mode=mode,
        )
    )
    assert result.validation_messages == []
    return result.pixels


@pytest.mark.parametrize("mode", ["instanced", "per_entity", "indirect"])
def test_mirrored_entities_keep_their_outside_faces(monkeypatch, tmp_path, mode):
    """A cube mirrored in x is the same cube: with the winding not flipped for it, back-face
    culling would show its inside instead."""
    plain = render_custom(build_cubes([(1, 1, 1)]), monkeypatch, tmp_path, mode)
    mirrored = render_custom(build_cubes([(-1, 1, 1)]), monkeypatch, tmp_path, mode)
    mean, outliers = image_difference(plain, mirrored)
    assert mean < 0.5 and outliers < 0.002
    # and both are right: the plain cube as the instanced mode draws it (two wrong windings
    # would also match each other)
    reference = plain if mode == "instanced" else render_custom(build_cubes([(1, 1, 1)]), monkeypatch, tmp_path)
    mean, outliers = image_difference(plain, reference)
    assert mean < 0.5 and outliers < 0.002
    assert plain[..., :3].max() > 30  # something was drawn


def test_degenerate_scales_render_without_validation_errors(monkeypatch, tmp_path):
    pixels = render_custom(build_cubes([(0, 1, 1), (0, 0, 0), (1e-20, 1, 1), (1, 1, 1)]), monkeypatch, tmp_path)
    assert pixels[..., :3].max() > 30


def test_scene_without_lights_builds_no_light_pipeline():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu() as gpu:
        world = World()
        build_cubes([(1, 1, 1)])(world, gpu.meshes.add)
        world.destroy(world.query(PointLight).entities())
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        default_schedule().run(world, 0.0)
        stats = renderer.render(world, readback=True)
        assert stats.draws == 1 and stats.lights == 0
        assert renderer.output.light_pass.pipeline is None  # made the first frame a scene has lights
        world.spawn(Transform(position=(1.5, 2.5, 2.5)), PointLight())
        stats = renderer.render(world, readback=True)
        assert stats.draws == 2 and stats.lights == 1 and renderer.output.light_pass.pipeline is not None
        assert gpu.target.pixels()[..., :3].max() > 30
        handle = gpu.meshes.add(cube_mesh())
        assert gpu.meshes.add(gpu.meshes[handle].data) == handle  # a mesh is uploaded once
        count = len(gpu.meshes)
        assert gpu.meshes.add(cube_mesh()) == handle and len(gpu.meshes) == count  # an equal one too


def test_upload_buffers_are_mapped_device_memory_or_host_memory_when_that_runs_out(monkeypatch):
    from ecs_engine.errors import UsageError
    from ecs_engine.gpu.allocator import BlockAllocator
    from ecs_engine.gpu.memory import HOST, UPLOAD, Buffer

    with headless_gpu() as gpu:
        device, vk = gpu.device, gpu.device.vk
        props = device.allocator.memory_properties
        buffer = Buffer(device, 4096, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, UPLOAD)
        try:
            flags = props.memoryTypes[device.allocator._memory_type(0xFFFFFFFF, UPLOAD)].propertyFlags
            assert flags & vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT
            buffer.array(np.uint32)[:] = 7  # mapped
            assert buffer.array(np.uint32)[-1] == 7
        finally:
            buffer.destroy()
        real = BlockAllocator._allocate
        asked = []

        def bar_full(self, requirements, where, kind):
            asked.append(where)
            if where == UPLOAD:
                raise UsageError("out of GPU memory allocating 64 MiB")
            return real(self, requirements, where, kind)

        monkeypatch.setattr(BlockAllocator, "_allocate", bar_full)
        fallback = Buffer(device, 4096, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, UPLOAD)
        try:
            assert asked == [UPLOAD, HOST]
            fallback.array(np.uint32)[:] = 3
            assert fallback.array(np.uint32)[0] == 3
        finally:
            fallback.destroy()


def test_suballocator_serves_many_buffers_from_few_allocations():
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance
    from ecs_engine.gpu.memory import DEVICE, HOST, Buffer, upload

    instance = Instance(validate=True)
    device = Device(instance)
    vk = device.vk
    try:
        buffers = [Buffer(device, 1000 + i, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, HOST) for i in range(200)]
        buffers += [Buffer(device, 4096, vk.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, DEVICE) for _ in range(50)]
        assert device.allocator.allocate_calls <= 3
        arr = buffers[3].array(np.float32)
        arr[:] = np.arange(len(arr))
        assert buffers[3].array(np.float32)[-1] == len(arr) - 1  # mapped: the same memory
        spans = sorted((b.allocation.offset, b.allocation.offset + b.size) for b in buffers[:200])
        assert all(a_end <= b_start for (_, a_end), (b_start, _) in itertools.pairwise(spans))  # no overlap
        data = np.arange(1000, dtype=np.uint32)
        gpu = upload(device, data, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
        back = Buffer(device, data.nbytes, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
        region = vk.VkBufferCopy(srcOffset=0, dstOffset=0, size=data.nbytes)
        device.submit_once(lambda cb: vk.vkCmdCopyBuffer(cb, gpu.handle, back.handle, 1, [region]))
        assert np.array_equal(back.array(np.uint32, 1000), data)  # the staging upload arrived
        for b in [*buffers, gpu, back]:
            b.destroy()
        assert device.allocator.stats()["used_bytes"] == 0
    finally:
        device.destroy()
        instance.destroy()
    assert instance.messages == []


def test_what_the_renderer_keeps_between_frames_follows_the_world():
    """Chunks, uniforms and camera matrices are kept while unchanged: each change must show."""
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(80, 60) as gpu:
        world = World()
        build_cubes([(1, 1, 1)])(world, gpu.meshes.add)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        schedule = default_schedule()

        def frame() -> tuple[object, np.ndarray]:
            schedule.run(world, 0.0)
            stats = renderer.render(world, readback=True)
            return stats, gpu.target.pixels()[..., :3].astype(int)

        for _ in range(3):  # every frame slot holds this state
            stats, base = frame()
        assert stats.instances == 1 and stats.lights == 1
        cube = world.query(Mesh).entities()[0]
        handle = int(world.get(cube, Mesh).handle)
        world.spawn(Transform(position=(-1.0, 0.5, 0.0), scale=(0.5, 0.5, 0.5)), Mesh(handle=handle))
        stats, more = frame()
        assert stats.instances == 2 and np.abs(more - base).max() > 30
        renderer.ambient = (1.0, 1.0, 1.0, 0.9)
        frame()
        stats, brighter = frame()  # both slots rewritten
        assert brighter.sum() > more.sum() * 1.2
        world.spawn(Transform(position=(-2.0, -2.0, 2.0)), PointLight(color=(1.0, 0.2, 0.2), intensity=6.0))
        stats, lit = frame()
        assert stats.lights == 2 and np.abs(lit - brighter).max() > 10
        camera = world.query(Camera).entities()[0]
        world.set(camera, Transform, position=world.get(camera, Transform).position + (0.0, 0.0, 3.0))
        stats, away = frame()
        covered = lambda image: (np.abs(image - image[0, 0]).max(axis=-1) > 8).sum()
        assert covered(away) < 0.8 * covered(lit)  # the cubes look smaller
        world.set(cube, Mesh, handle=99)
        with pytest.raises(ValueError, match=r"Mesh\.handle 99"):
            frame()
        world.set(cube, Mesh, handle=handle)
        frame()


def test_a_renderer_switched_to_another_world_draws_that_world():
    """Two worlds built the same way have tables with the same ids, layouts and ticks: what the
    renderer keeps from one must not be used for the other (the editor's scene switcher)."""
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(80, 60) as gpu:
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        cube = gpu.meshes.add(cube_mesh())
        sides = []
        for x in (-1.2, 1.2):
            world = World()
            world.spawn(Transform(position=(x, 0.0, 0.0)), Mesh(handle=cube))
            add_camera(world, eye=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0))
            default_schedule().run(world, 0.0)  # systems belong to one world (change ticks)
            renderer.render(world, readback=True)
            image = gpu.target.pixels()[..., :3].astype(int)
            covered = np.abs(image - image[0, 0]).max(axis=-1) > 8
            sides.append(np.argwhere(covered)[:, 1].mean())
        assert sides[0] < 40 < sides[1]  # left of centre, then right
