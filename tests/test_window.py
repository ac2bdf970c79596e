"""A windowed run under Xvfb: GLFW window, surface, swapchain, a resize and a minimise/restore."""

from __future__ import annotations

import os

import pytest

from ecs_engine.app.settings import RunOptions
from ecs_engine.app.window import open_glfw, run_windowed

pytestmark = pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")


def test_window_renders_resizes_and_survives_minimise(monkeypatch):
    glfw = open_glfw()
    assert glfw is not None, "DISPLAY is set but GLFW could not initialise"
    real_size = glfw.get_framebuffer_size
    state = {"minimised": False, "turns": 0, "done": False}

    def framebuffer_size(window):
        # Xvfb has no window manager, so iconify changes nothing there; report what GLFW
        # reports for a minimised window on a desktop (a 0x0 framebuffer) while "iconified".
        return (0, 0) if state["minimised"] else real_size(window)

    monkeypatch.setattr(glfw, "get_framebuffer_size", framebuffer_size)

    def script(frame, glfw_, window):
        # called at the top of every loop turn, also the ones spent minimised
        if frame == 4 and not state["turns"]:
            glfw_.set_window_size(window, 400, 300)
        if frame == 8 and not state["done"]:
            if not state["minimised"]:
                glfw_.iconify_window(window)
                state["minimised"] = True
            state["turns"] += 1
            if state["turns"] > 4:
                glfw_.restore_window(window)
                state["minimised"] = False
                state["done"] = True

    result = run_windowed(
        RunOptions(scene="cube", width=320, height=240, frames=16, validate=True, quiet=True), glfw, on_frame=script
    )
    assert result.validation_messages == []
    assert result.frames == 16
    assert result.recreations >= 1  # the resize rebuilt the swapchain
    assert result.minimised_waits >= 4  # no rendering while minimised
    assert len(result.gpu_ms) >= 10 and min(result.gpu_ms) > 0


def test_screenshot_of_a_window_is_the_presented_image(tmp_path, monkeypatch):
    """--screenshot in a window writes the last frame as presented (read back from the
    swapchain image); F12 writes one at any time."""
    from dataclasses import replace

    import numpy as np
    from PIL import Image

    from ecs_engine.app.loop import run
    from ecs_engine.app.window import WindowSource

    glfw = open_glfw()
    assert glfw is not None
    monkeypatch.chdir(tmp_path)
    holder = {}

    def press_f12(frame, glfw_, window):
        if frame == 3:
            holder["source"].request_screenshot()

    source = holder["source"] = WindowSource(glfw, on_frame=press_f12)
    shot = tmp_path / "window.png"
    options = RunOptions(scene="cube", width=200, height=150, frames=8, validate=True, quiet=True, screenshot=str(shot))
    result = run(replace(options, headless=False), source)
    assert result.validation_messages == [] and result.frames == 8
    image = np.asarray(Image.open(shot))
    assert image.shape == (150, 200, 3) and image.max() > 30  # the cube, lit
    assert len(source.shots) == 1  # F12 with --screenshot writes to that path too
    r, _g, b = image[0, 0].astype(int)
    assert abs(r - 39) <= 3 and abs(b - 48) <= 3 and b > r  # the clear colour (sRGB), in RGB order, not BGR


def test_two_hundred_resizes_and_minimises_while_rendering(monkeypatch):
    """Sizes from 1x1 up, back to the start, minimised and restored in between: no crash, no
    validation message, and the same GPU memory in use at the end as at the start."""
    glfw = open_glfw()
    assert glfw is not None
    real_size = glfw.get_framebuffer_size
    state = {"minimised": 0}
    monkeypatch.setattr(glfw, "get_framebuffer_size", lambda w: (0, 0) if state["minimised"] else real_size(w))
    sizes = [(1, 1), (2, 1), (1, 3)] + [(1 + (i * 37) % 400, 1 + (i * 53) % 300) for i in range(197)]
    used = {}
    holder = {}
    seen = set()  # swapchain sizes drawn at

    def script(frame, glfw_, window):
        source = holder["source"]
        seen.add((source.swapchain.width, source.swapchain.height))
        if state["minimised"]:
            state["minimised"] -= 1  # stays minimised for a few turns, then restored
            return
        if frame == 2:
            used["start"] = source.swapchain.device.allocator.stats()["used_bytes"]
        if 3 <= frame < 3 + len(sizes):
            glfw_.set_window_size(window, *sizes[frame - 3])
            if frame % 40 == 0:
                state["minimised"] = 3
        if frame == 3 + len(sizes):
            glfw_.set_window_size(window, 160, 120)  # back to the start
        if frame == 6 + len(sizes):
            used["end"] = source.swapchain.device.allocator.stats()["used_bytes"]

    from dataclasses import replace

    from ecs_engine.app.loop import run
    from ecs_engine.app.window import WindowSource

    source = holder["source"] = WindowSource(glfw, on_frame=script)
    options = RunOptions(scene="cube", width=160, height=120, frames=8 + len(sizes), validate=True, quiet=True)
    result = run(replace(options, headless=False), source)
    assert result.validation_messages == [] and result.frames == 8 + len(sizes)
    assert result.recreations >= 150 and result.minimised_waits >= 10
    assert used["end"] == used["start"]
    assert (1, 1) in seen and len(seen) > 150  # it really drew at 1x1 and at the other sizes


def resized_run(**settings) -> None:
    """8 frames in a 240x180 window that becomes 300x200 at frame 3, validation on: clean."""
    glfw = open_glfw()
    assert glfw is not None

    def script(frame, glfw_, window):
        if frame == 3:
            glfw_.set_window_size(window, 300, 200)

    options = RunOptions(width=240, height=180, frames=8, validate=True, quiet=True, **settings)
    result = run_windowed(options, glfw, on_frame=script)
    assert result.validation_messages == [] and result.frames == 8
    assert result.recreations >= 1


@pytest.mark.parametrize("msaa", [1, 4])
def test_a_window_with_msaa_and_a_filmic_tone_map_resizes_cleanly(msaa):
    """The swapchain's shared attachments (multisampled depth and HDR colour, the resolve) are
    made again on resize, with validation on. Without MSAA the swapchain starts drawing straight
    into its images and the renderer switches it to HDR colour for the tone map."""
    resized_run(scene="cube", msaa=msaa, tone_map="aces")


def test_a_deferred_window_resizes_cleanly():
    """The swapchain's G-buffer and the lighting's image set are made again on resize, with
    validation on."""
    resized_run(scene="lights", light_culling="deferred", lights=64)


def test_a_window_with_shadows_resizes_cleanly():
    """Shadow maps do not belong to the swapchain: a resize leaves them, with validation on."""
    resized_run(scene="shadows", light_culling="deferred")


def test_a_display_that_refuses_for_a_moment_is_asked_again(monkeypatch):
    """glfw.init failing once (a busy X server) still opens the window; failing every time
    falls back to headless (None), after three asks."""
    import sys
    import types

    import ecs_engine.app.window as window_module

    answers: list[bool] = []
    fake = types.SimpleNamespace(set_error_callback=lambda cb: None, init=lambda: answers.pop(0))
    monkeypatch.setitem(sys.modules, "glfw", fake)
    monkeypatch.setenv("DISPLAY", ":99")
    monkeypatch.setattr(window_module.time, "sleep", lambda s: None)
    answers[:] = [False, True]
    assert window_module.open_glfw() is fake and answers == []
    answers[:] = [False, False, False, True]
    assert window_module.open_glfw() is None and answers == [True]
