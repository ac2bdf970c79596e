"""Esc quits (issue 33): the demo, the editor and `play asteroids`, headless and windowed, from an
input script or a real key (a key event sent to the X server under Xvfb). A run with --screenshot
draws one more frame, read back, and writes it."""

from __future__ import annotations

import ctypes
import os
from contextlib import contextmanager
from pathlib import Path

import pytest

from ecs_engine.app.loop import run
from ecs_engine.app.settings import RunOptions

ESCAPE = "3 down escape\n4 up escape\n"
windowed = pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")


def script(tmp_path: Path, text: str = ESCAPE) -> str:
    path = tmp_path / "quit.txt"
    path.write_text(text)
    return str(path)


def options(tmp_path: Path, **kw) -> RunOptions:
    kw.setdefault("input_script", script(tmp_path))
    kw = {"width": 96, "height": 64, **kw}
    return RunOptions(scene="cube", frames=40, validate=True, quiet=True, **kw)


def test_a_scripted_esc_ends_a_headless_demo(tmp_path):
    result = run(options(tmp_path))
    assert result.frames == 4 < 40 and result.validation_messages == []


def test_with_a_screenshot_the_frame_after_esc_is_written(tmp_path):
    png = tmp_path / "last.png"
    result = run(options(tmp_path, screenshot=str(png)))
    assert result.frames == 5 and png.is_file() and result.pixels is not None


def test_a_scripted_esc_ends_a_headless_game(tmp_path, capsys):
    from ecs_engine.app.cli import main

    code = main(
        ["play", "asteroids", "--headless", "--width", "96", "--height", "64", "--frames", "40"]
        + ["--input-script", script(tmp_path)]
    )
    out = capsys.readouterr().out
    assert code == 0 and "\nframe 4: " in out, out


def test_a_scripted_esc_ends_a_headless_editor_run(tmp_path):
    pytest.importorskip("imgui_bundle")
    result = run(options(tmp_path, editor=True, scenes=("cube",), width=320, height=240))
    assert result.frames == 4 and result.validation_messages == []


@contextmanager
def x_display():
    """Xlib (ctypes) and a connection to the X server the tests run under (Xvfb)."""
    x11 = ctypes.CDLL("libX11.so.6")
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x11.XSetInputFocus.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_ulong]
    x11.XKeysymToKeycode.argtypes = [ctypes.c_void_p, ctypes.c_ulong]
    x11.XWarpPointer.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_ulong] + [ctypes.c_int] * 2
    x11.XWarpPointer.argtypes += [ctypes.c_uint] * 2 + [ctypes.c_int] * 2
    x11.XSync.argtypes = [ctypes.c_void_p, ctypes.c_int]
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    display = x11.XOpenDisplay(None)
    assert display, "no X display"
    try:
        yield x11, display
        x11.XSync(display, 0)
    finally:
        x11.XCloseDisplay(display)


def press_escape_on(glfw, window) -> None:
    """A real Esc: a key press and release sent to the X server (XTest), to the focused window."""
    xtst = ctypes.CDLL("libXtst.so.6")
    xtst.XTestFakeKeyEvent.argtypes = [ctypes.c_void_p, ctypes.c_uint, ctypes.c_int, ctypes.c_ulong]
    with x_display() as (x11, display):
        x11.XSetInputFocus(display, glfw.get_x11_window(window), 1, 0)  # RevertToPointerRoot, CurrentTime
        code = x11.XKeysymToKeycode(display, 0xFF1B)  # XK_Escape
        xtst.XTestFakeKeyEvent(display, code, 1, 0)
        xtst.XTestFakeKeyEvent(display, code, 0, 0)


def real_escape_at(frame: int):
    def on_frame(done, glfw, window) -> None:
        if done == frame:
            press_escape_on(glfw, window)

    return on_frame


@windowed
@pytest.mark.parametrize("editor", [False, True])
def test_esc_quits_a_window_scripted_or_real(tmp_path, editor):
    from dataclasses import replace

    from ecs_engine.app.window import open_glfw, run_windowed

    if editor:
        pytest.importorskip("imgui_bundle")
    extra = {"editor": True, "scenes": ("cube",)} if editor else {}
    glfw = open_glfw()
    assert glfw is not None
    scripted = run_windowed(replace(options(tmp_path, **extra), headless=False), glfw)
    assert scripted.frames == 4 and scripted.validation_messages == []
    glfw = open_glfw()
    real = run_windowed(replace(options(tmp_path, input_script=None, **extra), headless=False), glfw, real_escape_at(3))
    assert real.frames == 4 and real.validation_messages == []


@windowed
def test_a_scripted_esc_ends_a_windowed_game(tmp_path, capsys):
    from ecs_engine.app.cli import main

    code = main(
        ["play", "asteroids", "--width", "96", "--height", "64", "--frames", "40", "--input-script", script(tmp_path)]
    )
    out = capsys.readouterr().out
    assert code == 0 and "window 96x64" in out and "\nframe 4: " in out, out
