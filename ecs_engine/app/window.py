"""Windowed runs: a GLFW window with a Vulkan surface and swapchain, keyboard to the fly camera.

The swapchain is recreated when the window is resized; while it is minimised (a framebuffer of
size 0) the loop waits for events instead of rendering.
"""

from __future__ import annotations

import importlib
import os
import time
from collections.abc import Callable
from typing import Any

from .run import RunOptions, RunResult, build_scene, describe_device, job_pool, scene_builder, summary_line
from ..errors import UsageError

# GLFW key -> the names FlyCameraSystem reads (the seed's Table 7.1).
KEY_NAMES = {
    "KEY_LEFT": "left", "KEY_RIGHT": "right", "KEY_UP": "up", "KEY_DOWN": "down",
    "KEY_W": "w", "KEY_S": "s", "KEY_A": "a", "KEY_D": "d", "KEY_E": "e", "KEY_Q": "q",
}
MAX_DT = 0.1  # a hitch (dragging the window, a breakpoint) must not fling the camera (per-frame stages)
SIM_STEP = 1.0 / 120.0  # the fixed simulation step of windowed runs (timestep.FixedTimestep)


def key_names(glfw: Any) -> dict[int, str]:
    return {getattr(glfw, k): v for k, v in KEY_NAMES.items()}


def apply_key(glfw: Any, names: dict[int, str], keys: Any, key: int, action: int) -> None:
    """A GLFW key event into the InputState resource (key repeat changes nothing)."""
    name = names.get(key)
    if name is None:
        return
    if action == glfw.PRESS:
        keys.pressed.add(name)
    elif action == glfw.RELEASE:
        keys.pressed.discard(name)


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
    if not glfw.init():
        return None
    return glfw


def run_windowed(options: RunOptions, glfw: Any,
                 on_frame: Callable[[int, Any, Any], None] | None = None) -> RunResult:
    """Run until the window closes or `options.frames` frames were presented.
    `on_frame(frame_index, glfw, window)` is called before each frame (tests drive resizes)."""
    from .editor_session import EditorSession, SceneState
    from ..gpu.device import Device
    from ..gpu.functions import instance_function
    from ..gpu.instance import Instance
    from ..gpu.swapchain import OutOfDate, Swapchain
    from ..jobs import default_threads
    from ..render.mesh_registry import MeshRegistry
    from .perf import PerfMonitor
    from ..systems import InputState
    from ..ecs.timestep import FixedTimestep

    say = (lambda text: None) if options.quiet else print
    build = scene_builder(options.scene, options.entities)
    result = RunResult()
    perf = result.perf = PerfMonitor(log=options.perf_json or False)
    instance = device = swapchain = meshes = surface = window = state = session = None
    jobs = job_pool(options)
    try:
        glfw.window_hint(glfw.CLIENT_API, glfw.NO_API)
        window = glfw.create_window(options.width, options.height, f"ecs_engine - {options.scene}", None, None)
        if not window:
            raise UsageError("could not open a window (GLFW); run with --headless")
        extensions = list(glfw.get_required_instance_extensions() or [])
        instance = Instance(validate=options.validate, extensions=extensions)
        vk = instance.vk
        surface_ptr = vk.ffi.new("VkSurfaceKHR*")
        if glfw.create_window_surface(instance.handle, window, None, surface_ptr) != vk.VK_SUCCESS:
            raise UsageError("could not create a Vulkan surface for the window; run with --headless")
        surface = surface_ptr[0]
        device = Device(instance, surface=surface)
        result.device = describe_device(device)
        swapchain = Swapchain(device, surface, lambda: glfw.get_framebuffer_size(window), options.present)
        meshes = MeshRegistry(device)
        world, schedule, renderer = build_scene(options, build, device, swapchain, meshes, jobs)
        keys = world.resources[InputState] = InputState()
        resized = [False]

        names = key_names(glfw)

        def on_key(_win: Any, key: int, _code: int, action: int, _mods: int) -> None:
            if key == glfw.KEY_ESCAPE and action == glfw.PRESS:
                glfw.set_window_should_close(window, True)
            apply_key(glfw, names, keys, key, action)

        glfw.set_key_callback(window, on_key)
        glfw.set_framebuffer_size_callback(window, lambda *_: resized.__setitem__(0, True))
        state = SceneState(options, world, schedule, renderer, jobs, device, swapchain, meshes)
        if options.editor:  # after our callbacks: ImGui's GLFW backend chains to them
            session = result.editor = EditorSession(state, options.scenes, default_threads(),
                                                    len(renderer.frames.frames), window=window)
        say(f"{options.scene}: window {swapchain.width}x{swapchain.height} on {result.device}, present {options.present}")
        clock = FixedTimestep(SIM_STEP)
        start = previous = time.perf_counter()
        frame_no = 0
        while not glfw.window_should_close(window) and (options.frames is None or frame_no < options.frames):
            if on_frame is not None:
                on_frame(frame_no, glfw, window)
            glfw.poll_events()
            w, h = glfw.get_framebuffer_size(window)
            if w == 0 or h == 0:  # minimised: nothing to draw into
                glfw.wait_events_timeout(0.05)
                previous = time.perf_counter()
                result.minimised_waits += 1
                continue
            if resized[0] or (w, h) != (swapchain.width, swapchain.height):
                resized[0] = False
                swapchain.recreate()
            now = time.perf_counter()
            dt, previous = now - previous, now
            t0 = now
            if session is not None:  # keys typed into the UI do not fly the camera
                keys.keyboard_captured_by_ui = session.wants_keyboard
            state.schedule.run_frame(state.world, dt, clock, max_frame_dt=MAX_DT)
            if session is not None:
                session.build(state, result.last_stats, perf, dt, swapchain.width, swapchain.height)
            renderer = state.renderer
            frame = renderer.frames.frames[renderer.frames.index]
            w0 = time.perf_counter()
            renderer.frames.wait(frame)  # the semaphore below is free once this frame is done
            try:
                index, suboptimal = swapchain.acquire(frame.image_available)  # may block on vsync
            except OutOfDate:
                swapchain.recreate()
                continue
            waited_ms = (time.perf_counter() - w0) * 1e3
            stats = renderer.render(state.world, framebuffer=swapchain.framebuffers[index],
                                    extent=(swapchain.width, swapchain.height),
                                    wait=frame.image_available, signal=swapchain.render_finished[index])
            end = time.perf_counter()
            result.add_frame(stats, (end - t0) * 1e3 - stats.wait_ms - waited_ms, end, waited_ms,
                             ui_ms=session.cost_ms if session is not None else None)
            if not swapchain.present(index) or suboptimal:
                resized[0] = True
            frame_no += 1
            if perf.summary_due():
                say(perf.summary_line())
            if session is not None and session.apply_requests(state, swapchain):
                state.world.resources[InputState] = keys
        device.wait_idle()
        result.frames = frame_no
        result.wall_s = time.perf_counter() - start
        result.recreations = swapchain.recreations
        if frame_no:
            say(summary_line(result, frame_no, result.wall_s, final=True))
        result.write_perf_json(options, say)
    finally:
        if session is not None:
            session.destroy()
        for obj in (state.renderer if state else None, meshes, swapchain):
            if obj is not None:
                obj.destroy()
        if device is not None:
            device.destroy()
        if surface is not None:
            instance_function(instance, "vkDestroySurfaceKHR")(instance.handle, surface, None)
        if instance is not None:
            instance.destroy()
            result.validation_messages = list(instance.messages)
        if window is not None:
            glfw.destroy_window(window)
        glfw.terminate()
        (state.jobs if state else jobs).close()
    return result
