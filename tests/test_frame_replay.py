"""Frames submitted again instead of recorded again (render/frame/replay.py): a replayed frame
must draw exactly what recording it would have drawn, through every kind of change, and the
frames that cannot be replayed must record."""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, FlyCamera, Mesh, PointLight, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh, sphere_mesh
from ecs_engine.render.assets.textures import Texture
from ecs_engine.render.draw.path import ChunkResult
from ecs_engine.render.frame.replay import FrameReplay


def stripes(axis: int) -> np.ndarray:
    """16 x 16 RGBA, black and yellow stripes along `axis`."""
    image = np.zeros((16, 16, 4), np.uint8)
    image[..., 3] = 255
    band = (np.arange(16) // 4 % 2 == 0)[:, None] if axis == 0 else (np.arange(16) // 4 % 2 == 0)[None, :]
    image[..., 0] = image[..., 1] = np.where(band, 255, 0)
    return image


def test_replayed_frames_draw_what_recorded_frames_draw():
    """After each change, frames with replay on (some of them replayed) end on the image a
    recorded frame draws, and the change shows."""
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(80, 60) as gpu:
        world = World()
        registry = materials(world)  # a textured material from the start: the pipelines stay
        first = registry.add(Material("a", base_color_texture=registry.textures.add(Texture("a", stripes(0)))))
        cube = gpu.meshes.add(cube_mesh())
        cubes = [
            world.spawn(Transform(position=(x, 0.0, 0.0), scale=(0.6,) * 3), Mesh(handle=cube)) for x in (-1, 0, 1)
        ]
        world.set(cubes[0], Mesh, material=first)
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        world.spawn(Transform(position=(2.0, 3.0, 3.0)), PointLight(intensity=8.0))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        schedule = default_schedule()
        replay = renderer.replay

        def frame(on: bool = True) -> np.ndarray:
            replay.enabled = on
            schedule.run(world, 0.0)
            renderer.ensure_output()
            renderer.render(world, readback=True)
            return gpu.target.pixels()[..., :3].astype(int)

        last = [frame(on=False)]

        def step(change: Callable[[], object]) -> None:
            """The change, then frames until one is replayed: its image is a recorded frame's."""
            change()
            for _ in range(6):  # at most: both slots record what changed (a frame each), then once more
                replays = replay.replayed
                replayed = frame()
                if replay.replayed > replays:
                    break
            else:
                raise AssertionError("no frame was replayed")
            recorded = frame(on=False)
            assert np.array_equal(replayed, recorded)
            assert np.abs(recorded - last[0]).max() > 5  # the change shows
            last[0] = recorded

        def move() -> None:
            for i, e in enumerate(cubes):
                world.set(e, Transform, position=(i - 1.0, 0.4, -0.5))

        step(move)  # the rows move, the draws stay: replayed over the new rows
        # culled: one row fewer (the last written: a draw of the old count would show its old row)
        step(lambda: world.set(cubes[2], Transform, position=(40.0, 0.0, 0.0)))
        step(lambda: setattr(renderer, "ambient", (1.0, 1.0, 1.0, 0.5)))  # the frame's uniforms
        step(
            lambda: world.spawn(Transform(position=(-2.0, 1.0, 1.0)), PointLight(color=(1.0, 0.1, 0.1), intensity=10.0))
        )
        second = registry.add(Material("b", base_color_texture=registry.textures.add(Texture("b", stripes(1)))))
        step(lambda: world.set(cubes[1], Mesh, material=second))  # a texture page more: the sets are written
        sphere = gpu.meshes.add(sphere_mesh(16, 8))
        step(lambda: world.spawn(Transform(position=(0.0, -0.9, 1.0)), Mesh(handle=sphere)))  # a new mesh
        step(lambda: setattr(renderer, "exposure", 1.5))  # HDR: another form, its tone map pass
        step(lambda: setattr(renderer, "tone_map", "aces"))  # a push constant of the primary
        if gpu.device.features.get("fillModeNonSolid"):
            step(lambda: renderer.set_fill("wireframe"))  # new pipelines
        camera = world.query(Camera).entities()[0]
        yaw = float(world.get(camera, FlyCamera).yaw)
        # turned where it stands: no row is written (the origin stays), the planes cull others,
        # and turned back, what was culled is drawn again (a still frame's rows are kept while
        # the rows and the planes stay: chunk_paths.py)
        step(lambda: world.set(camera, FlyCamera, yaw=yaw - 1.0))
        step(lambda: world.set(camera, FlyCamera, yaw=yaw))
        step(lambda: world.set(camera, Transform, position=(0.0, 1.0, 6.0)))  # every row, the planes


def test_a_frame_is_replayed_only_into_the_framebuffer_it_was_recorded_for():
    """Twenty output images drawn in turn: the renderer keeps 16 outputs' states, so states are
    freed and made again (a new one may get a freed one's id) while no image is made. A
    replayed frame must be one its slot recorded for this output (the key holds the state
    itself, not its id); a review found 3 of 400 frames replayed into another output."""
    from ecs_engine.gpu.memory import Image
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(32, 24) as gpu:
        device, vk, target = gpu.device, gpu.device.vk, gpu.target
        world = World()
        world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        renderer = Renderer(device, target, gpu.meshes)
        gpu.owned.append(renderer)
        usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        images = [Image(device, 32, 24, target.color_format, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT) for _ in range(20)]
        framebuffers = images  # what `render` draws into: the offscreen target's output_image
        try:
            default_schedule().run(world, 0.0)
            recorded_for: dict[int, object] = {}
            replays = 0
            for f in range(400):
                framebuffer, slot = framebuffers[f % len(framebuffers)], renderer.frames.index
                stats = renderer.render(world, framebuffer=framebuffer, extent=(32, 24))
                if stats.replayed:
                    replays += 1
                    assert recorded_for[slot] is framebuffer, f
                else:
                    recorded_for[slot] = framebuffer
            assert replays == 0  # with an even count of framebuffers, a slot never meets the same one twice running
        finally:
            device.wait_idle()
            for image in images:
                image.destroy()


def test_still_rows_seen_by_a_still_camera_are_not_written_again(monkeypatch):
    """A slot's rows written from the same chunk, model ticks and planes are kept: only a
    change writes them again, in each slot once."""
    import ecs_engine.render.draw.chunk_paths as chunk_paths
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(32, 24) as gpu:
        world = World()
        cube = world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        schedule = default_schedule()
        writes = []
        write_rows = chunk_paths.write_rows
        monkeypatch.setattr(chunk_paths, "write_rows", lambda *a: writes.append(1) or write_rows(*a))

        def frames(n: int) -> int:
            writes.clear()
            for _ in range(n):
                schedule.run(world, 0.0)
                renderer.render(world)
            return len(writes)

        assert frames(4) >= 2  # each slot writes its rows (again after the first frames' new objects)
        replays = renderer.replay.replayed
        assert frames(6) == 0 and renderer.replay.replayed == replays + 6
        world.set(cube, Transform, position=(0.2, 0.0, 0.0))
        assert frames(4) == 2


def test_rows_another_culling_wrote_are_written_again(monkeypatch):
    """Rows the temporal culling decided (here: another set with the same counts) are never
    taken for the frustum culling's: back on frustum culling, with the camera still, the frame
    draws what a fresh renderer draws (a review found the kept result still said otherwise)."""
    from ecs_engine.render.extract.frame_data import FrameData
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(64, 48) as gpu:
        world = World()
        cube = gpu.meshes.add(cube_mesh())
        for x in (-1.0, 1.0, 60.0):  # two in view, one far out of it
            world.spawn(Transform(position=(x, 0.0, 0.0), scale=(0.8,) * 3), Mesh(handle=cube))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        world.spawn(Transform(position=(2.0, 3.0, 3.0)), PointLight(intensity=8.0))
        schedule = default_schedule()
        schedule.run(world, 0.0)

        def frames(renderer: Renderer, n: int) -> np.ndarray:
            for _ in range(n):
                schedule.run(world, 0.0)
                renderer.render(world, readback=True)
            return gpu.target.pixels()[..., :3].astype(int)

        fresh = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(fresh)
        expected = frames(fresh, 2)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        frames(renderer, 6)  # both slots keep their rows
        # the temporal culling keeps the first and the far cube: as many rows of the one mesh
        monkeypatch.setattr(FrameData, "visible", lambda self, chunk: np.array([True, False, True]))
        renderer.culling = "temporal"
        assert np.abs(frames(renderer, 2) - expected).max() > 5  # the second cube is missing
        monkeypatch.undo()
        renderer.culling = "frustum"
        assert np.array_equal(frames(renderer, 4), expected)


@pytest.mark.parametrize("scene", ["per_entity", "shadows", "blended"])
def test_frames_that_cannot_be_replayed_record(scene):
    from ecs_engine.components import Shadow
    from ecs_engine.render.assets.materials import Materials
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(64, 48) as gpu:
        world = World()
        cube = gpu.meshes.add(cube_mesh())
        material = 0
        if scene == "blended":
            materials = world.resources[Materials] = Materials()
            material = materials.add(Material(base_color=(0.2, 0.5, 1.0, 0.5), alpha_mode="blend"))
        world.spawn(Transform(), Mesh(handle=cube, material=material))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        light = world.spawn(Transform(position=(2.0, 3.0, 3.0)), PointLight(intensity=8.0))
        if scene == "shadows":
            world.add(light, Shadow())
        mode = "per_entity" if scene == "per_entity" else "instanced"
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode=mode)
        gpu.owned.append(renderer)
        default_schedule().run(world, 0.0)
        for _ in range(5):
            renderer.render(world, readback=True)
        assert renderer.replay.replayed == 0 and renderer.replay.recorded == 5


def chunk(cb: object, first: int, counts: bytes = b"\x01") -> ChunkResult:
    return ChunkResult(cb, 1, 1, 12, recorded=(first, 1, counts))


def test_a_slot_replays_only_when_every_chunk_came_back():
    replay = FrameReplay(2)
    assert replay.offer(0, ("k",)) is None  # nothing kept yet
    a, b = chunk("a", 0), chunk("b", 64)
    replay.keep(0, ("k",), [a, ChunkResult(None, 0, 0, 0), b], light_draws=1)
    assert replay.offer(1, ("k",)) is None  # another slot
    kept = replay.offer(0, ("k",))
    assert kept == {0: a, 64: b}
    again = replay.replay(0, [a, b])
    assert again is not None and again.light_draws == 1 and replay.replayed == 1
    assert replay.offer(0, ("other",)) is None  # another key drops what was kept
    assert replay.offer(0, ("k",)) is None
    replay.keep(0, ("k",), [a, b], 0)
    replay.offer(0, ("k",))
    assert replay.replay(0, [a, chunk("b2", 64)]) is None  # one chunk recorded anew: the primary too
    assert replay.offer(0, ("k",)) is None  # and the slot starts clean
    replay.keep(0, ("k",), [a, b], 0)
    replay.offer(0, ("k",))
    assert replay.replay(0, [a]) is None  # a chunk fewer (nothing visible in it)
    assert (replay.replayed, replay.recorded) == (1, 5)  # every frame counted once: replayed or recorded
    replay.keep(0, None, [a], 0)  # a frame that may not be replayed keeps nothing
    assert replay.offer(0, None) is None and replay.offer(0, ("k",)) is None
    replay.keep(0, ("k",), [SimpleNamespace(command_buffer="x", recorded=None)], 0)  # type: ignore[list-item]
    assert replay.offer(0, ("k",)) is None  # a chunk that cannot say what it recorded


def test_the_flag_turns_reuse_off_and_the_session_back_on():
    from dataclasses import replace

    from ecs_engine.app.cli import build_parser
    from ecs_engine.app.offscreen import OffscreenSource
    from ecs_engine.app.session import Session
    from ecs_engine.app.settings import RunOptions

    args = build_parser().parse_args(["demo", "cube", "--no-frame-reuse"])
    options = replace(RunOptions.from_flags(args, scene="cube"), width=64, height=48, threads=1)
    assert options.frame_reuse is False and RunOptions().settings().frame_reuse is True
    source = OffscreenSource()
    with Session(options, source) as session:
        replay = session.renderer.replay

        def frames(n: int) -> None:
            for _ in range(n):
                session.schedule.run(session.world, 0.0)
                session.renderer.render(session.world)

        frames(4)
        assert session.settings.frame_reuse is False and replay.replayed == 0
        session.apply(replace(session.settings, frame_reuse=True))
        frames(4)
        assert session.settings.frame_reuse is True and replay.replayed >= 2
    assert source.validation_messages() == []
