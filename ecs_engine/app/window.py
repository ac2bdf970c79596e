"""The window frame source: a GLFW window with a Vulkan surface and swapchain, keyboard, mouse
and gamepads (polled once a frame, gamepads.py) into the InputState resource of the session's
world, wall-clock time.

The swapchain is recreated when the window is resized; while it is minimised (a framebuffer of
size 0) no frame is drawn and the loop waits for events.
"""

from __future__ import annotations

import importlib
import os
import time
from collections.abc import Callable
from typing import Any

from ..ecs.timestep import FixedTimestep
from ..ecs.world import World
from ..errors import UsageError
from ..gpu.device import Device
from ..gpu.functions import instance_function
from ..gpu.instance import Instance
from ..gpu.swapchain import OutOfDate, Swapchain
from ..render.assets.mesh_registry import MeshRegistry
from ..render.config import check_samples
from ..systems import ActionMap, InputState
from ..systems.input_state import input_names
from .gamepads import GamepadPoller
from .report import save_png
from .session import FrameTarget, Gpu, Session
from .settings import MAX_DT, SIM_STEP, RunOptions


def key_names(glfw: Any) -> dict[int, str]:
    """GLFW key code -> its name in InputState: every KEY_* constant, lower-case, without the
    prefix (the fly camera's "left", "w", ... and the games' "space", "r" among them)."""
    names = input_names()
    return {getattr(glfw, k): k[4:].lower() for k in dir(glfw) if k.startswith("KEY_") and k[4:].lower() in names}


def button_names(glfw: Any) -> dict[int, str]:
    return {
        glfw.MOUSE_BUTTON_LEFT: "mouse_left",
        glfw.MOUSE_BUTTON_RIGHT: "mouse_right",
        glfw.MOUSE_BUTTON_MIDDLE: "mouse_middle",
    }


def apply_key(glfw: Any, names: dict[int, str], keys: Any, key: int, action: int) -> None:
    """A GLFW key or mouse button event into the InputState resource (repeats change nothing)."""
    name = names.get(key)
    if name is None:
        return
    if action == glfw.PRESS:
        keys.press(name)
    elif action == glfw.RELEASE:
        keys.release(name)


def open_glfw() -> Any | None:
    """The glfw module, initialised, or None when there is no display to open a window on."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return None
    try:
        # first: imgui-bundle points pyGLFW at its own libglfw, so the editor's ImGui GLFW
        # backend and our window share one GLFW (two copies would not know each other's windows)
        importlib.import_module("imgui_bundle")  # imported for that side effect only
    except ImportError:
        pass
    try:
        import glfw
    except ImportError as exc:
        raise UsageError(f"the Python package `glfw` is missing ({exc}); run `make demo` to install it") from exc
    glfw.set_error_callback(lambda code, text: None)  # failures are reported through return values
    # a display that refuses a connection for a moment (a busy X server, Xvfb between clients)
    # is asked again before the run falls back to headless
    for wait in (0.1, 0.3, 0.0):
        if glfw.init():
            return glfw
        time.sleep(wait)
    return None


class WindowSource:
    """`on_frame(frames_done, glfw, window)` runs at the top of each loop turn, also the turns
    spent minimised (tests drive resizes with it).

    Screenshots read the presented image back: with --screenshot, the last frame (one more frame
    is drawn when the window is closed, so it is what the user saw); F12 writes one at any time,
    to the --screenshot path or to ecs_engine-<time>.png in the current folder."""

    def __init__(self, glfw: Any, on_frame: Callable[[int, Any, Any], None] | None = None) -> None:
        self.glfw = glfw
        self.on_frame = on_frame
        self.clock = FixedTimestep(SIM_STEP)
        self.max_frame_dt = MAX_DT
        self.window: Any = None
        self.input = InputState()
        self.gamepads = GamepadPoller()
        self.frames: int | None = None
        self.minimised_waits = 0
        self.instance: Instance | None = None  # its validation messages outlive the run
        self._surface: Any = None
        self._opened: list[Any] = []  # device-level objects to destroy, in the order made
        self._resized = False
        self._previous = time.perf_counter()
        self.screenshot: str | None = None  # the --screenshot path
        self._shot_requested = False  # F12: read back the next frame and write it
        self._final_shot = False  # the window closes: one more frame, read back
        self._took_final = False
        self._slot = 0  # the renderer's frame slot when this frame began
        self.shots: list[str] = []  # files F12 wrote

    # ----------------------------------------------------------------- set-up
    def open(self, options: RunOptions) -> Gpu:
        glfw = self.glfw
        self.frames = options.frames
        self.screenshot = options.screenshot
        glfw.window_hint(glfw.CLIENT_API, glfw.NO_API)
        self.window = glfw.create_window(options.width, options.height, f"ecs_engine - {options.scene}", None, None)
        if not self.window:
            raise UsageError("could not open a window (GLFW); run with --headless")
        extensions = list(glfw.get_required_instance_extensions() or [])
        instance = self.instance = Instance(validate=options.validate, extensions=extensions)
        vk = instance.vk
        surface = vk.ffi.new("VkSurfaceKHR*")
        if glfw.create_window_surface(instance.handle, self.window, None, surface) != vk.VK_SUCCESS:
            raise UsageError("could not create a Vulkan surface for the window; run with --headless")
        self._surface = surface[0]
        device = self._keep(Device(instance, surface=self._surface))
        window = self.window
        check_samples(device, options.msaa)
        swapchain = self._keep(
            Swapchain(device, self._surface, lambda: glfw.get_framebuffer_size(window), options.present, options.msaa)
        )
        meshes = self._keep(MeshRegistry(device, background_levels=True))  # a window keeps drawing meanwhile
        self.swapchain = swapchain
        return Gpu(instance, device, swapchain, meshes)

    def _keep(self, obj: Any) -> Any:
        self._opened.append(obj)
        return obj

    def attach(self, session: Session) -> None:
        """Keys go to the InputState resource of whichever world the session runs."""
        glfw = self.glfw
        names = key_names(glfw)

        def on_key(_win: Any, key: int, _code: int, action: int, _mods: int) -> None:
            # Esc goes to the InputState like any key: the run loop quits on it, a script's too
            if key == glfw.KEY_F12 and action == glfw.PRESS:
                self.request_screenshot()
            apply_key(glfw, names, self.input, key, action)

        def give_input(world: World) -> None:
            world.resources[InputState] = self.input
            actions = world.resources.get(ActionMap)
            if actions is not None:
                actions.input = self.input  # the game's actions hear this window's keys

        buttons = button_names(glfw)

        def on_button(_win: Any, button: int, action: int, _mods: int) -> None:
            apply_key(glfw, buttons, self.input, button, action)

        glfw.set_key_callback(self.window, on_key)
        glfw.set_mouse_button_callback(self.window, on_button)
        glfw.set_cursor_pos_callback(self.window, lambda _w, x, y: self.input.move_mouse(float(x), float(y)))
        glfw.set_scroll_callback(
            self.window,
            lambda _w, x, y: setattr(self.input, "scroll", (self.input.scroll[0] + x, self.input.scroll[1] + y)),
        )
        glfw.set_char_callback(self.window, lambda _w, code: setattr(self.input, "text", self.input.text + chr(code)))
        glfw.set_framebuffer_size_callback(self.window, lambda *_: setattr(self, "_resized", True))
        give_input(session.world)
        session.on_world.append(give_input)
        self._previous = time.perf_counter()

    # -------------------------------------------------------------- per frame
    def running(self, frames_done: int) -> bool:
        closing = self.glfw.window_should_close(self.window) or (
            self.frames is not None and frames_done >= self.frames - (1 if self.screenshot else 0)
        )
        if closing and self.screenshot is not None and not self._took_final:
            self._final_shot = True  # one more frame, read back: the --screenshot
            return True
        return not closing

    def request_close(self) -> None:
        """Close the window after this frame (Esc); with --screenshot one more frame is read back."""
        self.glfw.set_window_should_close(self.window, True)

    def request_screenshot(self) -> None:
        """Read the next presented frame back and write it (F12)."""
        self._shot_requested = True

    def begin(self, session: Session, frames_done: int) -> FrameTarget | None:
        """Events, resize, then the next swapchain image; None when there is nothing to draw
        into this turn (minimised, or the swapchain went out of date)."""
        glfw, swapchain = self.glfw, self.swapchain
        if self.on_frame is not None:
            self.on_frame(frames_done, glfw, self.window)
        glfw.poll_events()
        self.gamepads.poll(glfw, self.input)
        width, height = glfw.get_window_size(self.window)  # the units of the mouse position
        self.input.viewport = (float(width), float(height))
        w, h = glfw.get_framebuffer_size(self.window)
        if w == 0 or h == 0:  # minimised: nothing to draw into
            glfw.wait_events_timeout(0.05)
            self._previous = time.perf_counter()
            self.minimised_waits += 1
            return None
        if self._resized or (w, h) != (swapchain.width, swapchain.height):
            self._resized = False
            swapchain.recreate()
        now = time.perf_counter()
        dt, self._previous = now - self._previous, now
        image_available = session.renderer.next_image_semaphore()  # waits until the next frame slot is free
        self._slot = session.renderer.frames.index  # abandon: did the frame get submitted?
        try:
            index, suboptimal = swapchain.acquire(image_available)  # may block on vsync
        except OutOfDate:
            swapchain.recreate()
            return None
        readback = self._final_shot or self._shot_requested
        if readback:
            swapchain.readback_image = index
        return FrameTarget(
            readback=readback,
            dt=dt,
            framebuffer=swapchain.framebuffers[index],
            extent=(swapchain.width, swapchain.height),
            wait=image_available,
            signal=swapchain.render_finished[index],
            waited_ms=(time.perf_counter() - now) * 1e3,
            image=index,
            suboptimal=suboptimal,
        )

    def end(self, session: Session, target: FrameTarget) -> None:
        if not self.swapchain.present(target.image) or target.suboptimal:
            self._resized = True
        if self._final_shot:
            self._final_shot, self._took_final = False, True
        if self._shot_requested and target.readback:  # the renderer waited for the frame
            self._shot_requested = False
            path = self.screenshot or time.strftime("ecs_engine-%Y%m%d-%H%M%S.png")
            pixels = self.swapchain.pixels()
            if pixels is not None:
                save_png(pixels, path)
                self.shots.append(path)
                print(f"wrote {path}")

    def abandon(self, session: Session, target: FrameTarget) -> None:
        """A frame that failed (a scene rolled back). Failed before its submit, it still holds an
        acquired image whose semaphore is signalled: an empty submit waits the semaphore out and
        the swapchain is made anew, which takes the image back unpresented (its pixels are
        undefined). Failed after, it is presented as it is."""
        if session.renderer.frames.index != self._slot:
            self.end(session, target)
            return
        device = self.swapchain.device
        vk = device.vk
        stage = vk.VK_PIPELINE_STAGE_ALL_COMMANDS_BIT
        vk.vkQueueSubmit(
            device.queue, 1, [vk.VkSubmitInfo(pWaitSemaphores=[target.wait], pWaitDstStageMask=[stage])], None
        )
        self.swapchain.recreate()  # after waiting for the device

    def describe(self, session: Session) -> str:
        return (
            f"{session.scene}: window {self.swapchain.width}x{self.swapchain.height}, "
            f"present {self.swapchain.present_name}"
        )

    @property
    def recreations(self) -> int:
        swapchain = getattr(self, "swapchain", None)
        return swapchain.recreations if swapchain is not None else 0

    @property
    def present_mode(self) -> str | None:
        return self.swapchain.present_name

    def check_present(self, present: str) -> None:
        self.swapchain.present_mode_for(present)

    def set_present(self, present: str) -> None:
        self.swapchain.set_present(present)

    def validation_messages(self) -> list[str]:
        return [] if self.instance is None else list(self.instance.messages)

    def pixels(self) -> Any:
        """The last frame read back (the --screenshot frame), as presented."""
        return self.swapchain.pixels()

    def close(self) -> None:
        while self._opened:
            self._opened.pop().destroy()
        if self._surface is not None and self.instance is not None:
            instance_function(self.instance, "vkDestroySurfaceKHR")(self.instance.handle, self._surface, None)
            self._surface = None
        if self.instance is not None:
            self.instance.destroy()
        if self.window is not None:
            self.glfw.destroy_window(self.window)
            self.window = None
        self.glfw.terminate()


def run_windowed(options: RunOptions, glfw: Any, on_frame: Callable[[int, Any, Any], None] | None = None) -> Any:
    """`loop.run` in a window (GLFW already opened with `open_glfw`); closes GLFW at the end."""
    from dataclasses import replace

    from .loop import run

    return run(replace(options, headless=False), WindowSource(glfw, on_frame))
