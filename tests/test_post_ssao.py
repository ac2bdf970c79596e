"""SSAO as the post effect "ssao" (render/post/ssao_effect.py) in the renderer, on lavapipe with
validation on: a floor and a box drawn with it on are the NumPy pipeline of the frame's own depth
and HDR colour (tests/ssao_reference.py, the composite, the clamp tone map); the crease darkens
and the open floor does not; the projection is part of the replay key; MSAA is refused (the
config's rule, the renderer, the CLI); the plugin line; the order ssao, bloom, fxaa."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
import ssao_reference as ref
from fxaa_reference import linear_to_srgb
from gpu_context import headless_gpu
from image_readback import record_copy_out

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform
from ecs_engine.components.camera import active_camera
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.primitives import cube_mesh, plane_mesh
from ecs_engine.render.config import RenderConfig, validate
from ecs_engine.render.post import registry
from ecs_engine.render.post.ssao import SsaoSettings

W, H = 64, 48
EYE, AIM = (2.2, 1.6, 2.6), (0.0, 0.3, 0.0)
REFUSAL = "--post ssao cannot draw with --msaa 4: SSAO reads single-sample depth (use --msaa 1)"


def _world(gpu: Any) -> World:
    """A 6 m floor, a 1 m box standing on it, a sun from above and the camera looking at the box."""
    world = World()
    world.spawn(Transform(), Mesh(handle=gpu.meshes.add(plane_mesh(6.0))))
    world.spawn(Transform(position=(0.0, 0.5, 0.0)), Mesh(handle=gpu.meshes.add(cube_mesh())))
    a = math.radians(-60.0)  # the light's -Z turned down about x
    world.spawn(Transform(rotation=(math.sin(a / 2), 0.0, 0.0, math.cos(a / 2))), DirectionalLight(illuminance=0.6))
    add_camera(world, eye=EYE, target=AIM)
    default_schedule().run(world, 0.0)
    return world


def _renderer(gpu: Any, target: Any = None, **settings: Any) -> Any:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, target or gpu.target, gpu.meshes, **settings)
    gpu.owned.append(renderer)
    return renderer


def _pixels(gpu: Any, renderer: Any, world: World) -> np.ndarray:
    renderer.ensure_output()
    renderer.render(world, readback=True)
    return gpu.target.pixels()[..., :3].astype(np.int64)


class InputsSpy:
    """An hdr-stage post effect run first: copies the frame's HDR colour and depth to host
    buffers (both images made with transfer usage for the test) and keeps the projection."""

    def __init__(self, device: Any) -> None:
        from ecs_engine.gpu.memory import Buffer

        vk = self.vk = device.vk
        dst = vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
        self.hdr_buffer, self.depth_buffer = Buffer(device, W * H * 8, dst), Buffer(device, W * H * 4, dst)
        self.projection: np.ndarray | None = None

    def _copy(self, cb: Any, image: Any, aspect: int, buffer: Any) -> None:
        vk = self.vk
        record_copy_out(vk, cb, image.handle, buffer, (W, H), vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, aspect)

    def __call__(self, cb: Any, inputs: Any) -> None:
        vk = self.vk
        assert inputs.extent == (W, H) and inputs.depth is not None
        self._copy(cb, inputs.hdr, vk.VK_IMAGE_ASPECT_COLOR_BIT, self.hdr_buffer)
        self._copy(cb, inputs.depth, vk.VK_IMAGE_ASPECT_DEPTH_BIT, self.depth_buffer)
        self.projection = np.array(inputs.projection, dtype=np.float64)

    def hdr(self) -> np.ndarray:
        return self.hdr_buffer.bytes()[: W * H * 8].view(np.float16).reshape(H, W, 4).astype(np.float32)

    def depth(self) -> np.ndarray:
        return self.depth_buffer.bytes()[: W * H * 4].view(np.float32).reshape(H, W).copy()

    def destroy(self) -> None:
        self.hdr_buffer.destroy()
        self.depth_buffer.destroy()


def _readable(monkeypatch: Any) -> None:
    """The scene's HDR colour and depth made with TRANSFER_SRC usage too (the spy copies them)."""
    from ecs_engine.gpu import scene_attachments as render_pass

    usage = render_pass.hdr_read_usage
    monkeypatch.setattr(render_pass, "hdr_read_usage", lambda d: usage(d) | d.vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT)
    image = render_pass.Image

    def made(device: Any, width: int, height: int, fmt: int, use: int, aspect: int, *rest: Any) -> Any:
        if aspect == device.vk.VK_IMAGE_ASPECT_DEPTH_BIT:
            use |= device.vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        return image(device, width, height, fmt, use, aspect, *rest)

    monkeypatch.setattr(render_pass, "Image", made)


def _world_positions(renderer: Any, world: World, depth: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """(H, W, 3) world positions of the depth's pixels (the camera's inverse view and position)."""
    camera = renderer.extract(world, W, H).camera
    y, x = np.mgrid[0:H, 0:W]
    ndc = np.stack([(x + 0.5) / W * 2 - 1, (y + 0.5) / H * 2 - 1, np.maximum(depth, 1e-9), np.ones((H, W))], -1)
    v = ndc @ np.linalg.inv(projection).T
    view = v[..., :3] / v[..., 3:4]
    return view @ np.asarray(camera.inverse_view, np.float64)[:3, :3].T + np.asarray(camera.position)


def test_ssao_in_the_renderer_is_the_reference_of_the_frames_depth(monkeypatch, tmp_path):
    """With ssao on, the frame is clamp(hdr * ao) of that frame's own HDR colour and depth, ao
    the NumPy GTAO + denoise (ssao_reference.py) within a level or two of 8-bit sRGB; the crease
    where the box meets the floor is darker than with ssao off, the open floor unchanged."""
    _readable(monkeypatch)
    with headless_gpu(W, H) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu)
        off = _pixels(gpu, renderer, world)
        assert gpu.target.form == "direct"
        renderer.set_post_effects({"ssao"})
        assert gpu.target.form == "hdr" and renderer.post_effects == ("ssao",)
        renderer.replay.enabled = False  # the spy is no part of the frame's key
        spy = InputsSpy(gpu.device)
        gpu.owned.append(spy)
        renderer.output.post.insert(0, spy)
        on = _pixels(gpu, renderer, world)
        renderer.output.post.remove(spy)
        depth, hdr, projection = spy.depth(), spy.hdr(), spy.projection
        assert projection is not None and (depth > 0).mean() > 0.6  # floor and box, sky at the top
        ao = ref.ssao(depth, projection, SsaoSettings()).astype(np.float16).astype(np.float32)
        composite = (hdr[..., :3] * ao[..., None]).astype(np.float16).astype(np.float64)
        want = np.round(linear_to_srgb(np.minimum(composite, 1.0)) * 255).astype(np.int64)
        error = np.abs(on - want)
        assert error.max() <= 2 and error.mean() < 0.35, (error.max(), error.mean())  # rounding: 1, 0.19
        plain = np.round(linear_to_srgb(np.minimum(hdr[..., :3].astype(np.float64), 1.0)) * 255)
        assert np.abs(off - plain).max() <= 1  # the hdr form's clamp is the direct form's frame

        p = _world_positions(renderer, world, depth, projection)
        floor = (depth > 0) & (p[..., 1] < 0.02)
        outside = np.maximum(np.abs(p[..., 0]), np.abs(p[..., 2])) - 0.5  # metres from the box's side
        crease, open_floor = floor & (outside < 0.15), floor & (outside > 1.2)
        assert crease.sum() > 10 and open_floor.sum() > 200
        luma_on, luma_off = on.sum(axis=2), off.sum(axis=2)
        assert (luma_on[crease] < luma_off[crease]).mean() > 0.9
        assert (luma_off[crease] - luma_on[crease]).mean() > 20  # visibly darker
        assert np.abs(luma_on[open_floor] - luma_off[open_floor]).mean() < 2  # nearly unchanged


def test_the_projection_is_in_the_replay_key_so_a_new_lens_is_never_replayed_stale():
    """With frame replay on, SSAO's key holds the projection: after a change of field of view,
    the frames shown are those of a renderer that never replays; and turning ssao on and off
    between replayed frames shows each change at once."""
    with headless_gpu(W, H) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu, post={"ssao"})
        replay = renderer.replay

        def settle() -> np.ndarray:
            first = _pixels(gpu, renderer, world)
            for _ in range(6):
                before = replay.replayed
                again = _pixels(gpu, renderer, world)
                if replay.replayed > before:
                    assert np.array_equal(again, first)
                    return again
            raise AssertionError("no frame was replayed")

        wide = settle()
        key = renderer.post_key()
        world.set(active_camera(world), Camera, fov_y=math.radians(35.0))
        narrow = settle()
        assert renderer.post_key() != key and np.abs(narrow - wide).max() > 8
        fresh = _renderer(gpu, post={"ssao"})
        fresh.replay.enabled = False
        assert np.abs(_pixels(gpu, fresh, world) - narrow).max() <= 1
        fresh.set_post_effects(set())
        renderer.set_post_effects(set())
        plain = settle()
        renderer.set_post_effects({"ssao", "bloom"})
        both = settle()
        renderer.set_post_effects({"ssao"})
        assert np.abs(settle() - narrow).max() <= 1 and np.abs(both - narrow).max() > 2
        assert np.abs(plain - narrow).max() > 8


def test_ssao_runs_before_bloom_and_in_the_deferred_form():
    """ssao, then bloom, in the hdr stage (whatever order they were asked in); the deferred
    form (light culling's choice) stores its depth for it too, validation-clean."""
    from ecs_engine.gpu.offscreen import OffscreenTarget

    assert registry.ordered({"fxaa", "bloom", "ssao"}) == ("ssao", "bloom", "fxaa")
    assert registry.kind("ssao").depth and registry.depth_readers({"bloom", "ssao"}) == ("ssao",)
    with headless_gpu(W, H) as gpu:
        target = OffscreenTarget(gpu.device, W, H)
        gpu.owned.append(target)
        world = _world(gpu)
        renderer = _renderer(gpu, target, light_culling="deferred")
        renderer.render(world, readback=True)
        off = target.pixels()[..., :3].astype(np.int64)
        renderer.set_post_effects({"bloom", "ssao"})
        assert [type(p).__name__ for p in renderer.output.post] == ["SsaoEffect", "BloomEffect"]
        renderer.render(world, readback=True)
        on = target.pixels()[..., :3].astype(np.int64)
        assert target.form == "deferred" and target.depth_image is not None
        assert (on.sum(axis=2) < off.sum(axis=2) - 20).sum() > 10  # darker somewhere (the crease)


def test_msaa_is_refused_by_the_config_the_renderer_and_the_cli(capsys):
    from ecs_engine.app.cli import main
    from ecs_engine.gpu.offscreen import OffscreenTarget

    assert validate(RenderConfig(post={"ssao", "bloom"}, msaa=4)) == [REFUSAL]
    assert validate(RenderConfig(post={"bloom"}, msaa=4)) == validate(RenderConfig(post={"ssao"})) == []
    with headless_gpu(W, H) as gpu:
        target = OffscreenTarget(gpu.device, W, H, samples=4)
        gpu.owned.append(target)
        assert target.depth_image is None  # a multisampled depth is not stored
        with pytest.raises(UsageError, match="SSAO reads single-sample depth"):
            _renderer(gpu, target, post={"ssao"})
        renderer = _renderer(gpu, target)
        with pytest.raises(UsageError, match="SSAO reads single-sample depth"):
            renderer.set_post_effects({"ssao"})
        assert renderer.post_effects == ()
    capsys.readouterr()
    assert main(["demo", "cube", "--headless", "--frames", "1", "--post", "ssao", "--msaa", "4"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and REFUSAL in err


def test_the_plugin_line_turns_ssao_on():
    from ecs_engine import App, DefaultPlugins, SsaoPlugin

    app = App(title="creases", size=(32, 24))
    app.add_plugins(DefaultPlugins, SsaoPlugin(SsaoSettings(radius=0.3)))
    seen = {}

    def look(world: Any, session: Any) -> None:
        seen["post"] = session.renderer.post_effects
        seen["ssao"] = session.renderer.post_settings["ssao"]
        seen["form"] = session.renderer.target.form

    app.on_open(look)
    app.add_startup_systems(lambda world, dt: add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0)))
    app.run(frames=2, headless=True)
    assert seen == {"post": ("ssao",), "ssao": SsaoSettings(radius=0.3), "form": "hdr"}
    with pytest.raises(UsageError, match="ssao settings must be SsaoSettings"):
        App().add_plugins(SsaoPlugin(RenderConfig()))
