"""The output after the scene's render pass (render/frame/output_passes.py), on lavapipe with validation
on: in the hdr and deferred forms the tone map and the overlay draw with dynamic rendering into
the target, after the post effects' seam, and give the pixels the direct form gives."""

from __future__ import annotations

import os

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, PointLight, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.assets.primitives import cube_mesh


def _cube_world(gpu):
    """A cube and a point light (its billboard drawn in the billboards' subpass)."""
    world = World()
    world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
    world.spawn(Transform(position=(1.5, 1.0, 1.0)), PointLight())
    add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
    default_schedule().run(world, 0.0)
    return world


def test_post_effects_run_between_the_scene_pass_and_the_tone_map(monkeypatch):
    """`OutputPasses.post` is called once a frame with the frame's PostInputs: the target's
    single-sample HDR colour (sampled-capable), its single-sample depth and the camera's
    projection, after the billboards' subpass ends and before the tone map; not in the direct
    form, which has no HDR colour."""
    from ecs_engine.render.frame.renderer import Renderer
    from ecs_engine.render.passes.light_billboards import LightPass
    from ecs_engine.render.passes.tone_map import ToneMapPass

    order: list[str] = []
    for cls, name in ((LightPass, "billboards"), (ToneMapPass, "tone map")):
        real = cls.record

        def logged(self, *args, _real=real, _name=name, **kwargs):
            order.append(_name)
            return _real(self, *args, **kwargs)

        monkeypatch.setattr(cls, "record", logged)
    with headless_gpu(32, 24) as gpu:
        world = _cube_world(gpu)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        seen = []

        def post(cb, inputs):
            order.append("post")
            seen.append(inputs)

        renderer.output.post.append(post)
        renderer.render(world, readback=True)
        assert order == ["billboards"] and not seen  # direct: straight into the target
        order.clear()
        renderer.tone_map = "aces"
        renderer.render(world, readback=True)
        assert order == ["billboards", "post", "tone map"]
        vk = gpu.device.vk
        image = gpu.target.hdr_image
        (inputs,) = seen
        assert inputs.hdr is image and image.format == vk.VK_FORMAT_R16G16B16A16_SFLOAT
        assert (image.width, image.height) == inputs.extent == (32, 24)
        depth = gpu.target.depth_image  # single-sample: stored for the effects that sample it
        assert inputs.depth is depth and depth.format == vk.VK_FORMAT_D32_SFLOAT
        camera = renderer.extract(world, 32, 24).camera
        assert np.array_equal(inputs.projection, camera.projection)


@pytest.mark.parametrize("form", ["hdr", "deferred"])
def test_the_tone_map_and_overlay_give_the_direct_forms_pixels(scene, form):
    """The clamp tone map at exposure 0 is what the direct form draws: the editor's frame (scene
    and UI) forced into the hdr or deferred form, whose tone map and overlay draw with dynamic
    rendering after the scene's render pass, matches it, the UI included; and without the
    overlay the UI's pixels are gone, so it was drawn there."""
    s = scene.state
    target = s.gpu.target
    scene.frame()  # the world's systems run here only: the frames compared draw the same world
    scene.frame()  # (the UI settles its docked layout over the first frames)
    assert not target.hdr

    def frame(overlay: bool = True) -> np.ndarray:
        scene.session.build(s.world, scene.stats, scene.perf, 1 / 60, *scene.size)
        kept = s.renderer.overlay
        s.renderer.overlay = kept if overlay else None
        try:
            # the target's own framebuffer named: the renderer follows a new form and keeps it
            s.renderer.render(s.world, readback=True, framebuffer=target.framebuffer)
        finally:
            s.renderer.overlay = kept
        return target.pixels()[..., :3].astype(int)

    direct = frame()
    s.device.wait_idle()
    target.set_form(form)
    with_ui = frame()
    assert target.form == form
    # 8-bit sRGB either way, but the HDR colour's half floats round some channels (the clear
    # colour's, across the scene) by one the other way; beyond that only the Perf window's
    # figures change from frame to frame
    assert (np.abs(with_ui - direct).max(axis=2) > 1).mean() < 0.001
    without = frame(overlay=False)
    assert (np.abs(with_ui - without).max(axis=2) > 24).mean() > 0.05


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_a_window_in_the_hdr_form_presents_and_reads_back_the_tone_mapped_image(tmp_path):
    """The swapchain image, drawn by the tone map's rendering, goes to PRESENT_SRC (presented
    eight times over resizes-free frames) and is read back from there: its background is the
    filmic curve's, as the offscreen target draws it."""
    from dataclasses import replace

    from PIL import Image

    from ecs_engine.app.loop import run
    from ecs_engine.app.settings import RunOptions
    from ecs_engine.app.window import WindowSource, open_glfw

    glfw = open_glfw()
    assert glfw is not None
    shots = {}
    for headless in (True, False):
        shot = tmp_path / f"{headless}.png"
        options = RunOptions(
            scene="cube", width=200, height=150, frames=8, validate=True, quiet=True, screenshot=str(shot)
        )
        options = replace(options, tone_map="aces", headless=headless)
        result = run(options, None if headless else WindowSource(glfw))
        assert result.validation_messages == [] and result.frames == 8
        shots[headless] = np.asarray(Image.open(shot))[..., :3].astype(int)
    window, offscreen = shots[False], shots[True]
    assert window.shape == (150, 200, 3) and window.max() > 30  # the cube, lit
    assert (window[0, 0] == offscreen[0, 0]).all()  # the background, tone mapped alike
    r, _g, b = window[0, 0]
    assert b > r and abs(r - 39) > 3  # RGB order, and not the clamp's clear colour
