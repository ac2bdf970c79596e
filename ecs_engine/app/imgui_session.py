"""One run's ImGui: the context, the Vulkan renderer that draws it (the renderer's overlay pass),
a rate limit on rebuilding it, and the GLFW backend when there is a window. The editor
(editor_session.py) and a game's HUD (play.py) build their windows on it.

The UI is rebuilt at most `max_ui_hz` times a second (default 120, a fast monitor's refresh);
frames in between draw the last UI again. A scene running at 2,000 FPS would otherwise spend
~0.2-0.3 ms of every frame rebuilding windows nobody can see change that fast; input waits in
ImGui's queue for at most one UI period. An input script's events (`feed`) reach ImGui the same
way, headless or in a window (imgui_input.py).
"""

from __future__ import annotations

import ctypes
import time
from typing import Any

from ..ecs.world import World
from ..render.ui.imgui_pass import ImGuiRenderer
from .imgui_input import ScriptedImGuiInput
from .perf import PerfMonitor
from .session import Session
from .settings import Settings


class ImGuiSession:
    def __init__(self, session: Session, window: Any = None, max_ui_hz: float | None = 120.0) -> None:
        from imgui_bundle import imgui, implot

        self.imgui, self.implot = imgui, implot
        self.context = imgui.create_context()
        self.plot_context = implot.create_context()
        io = imgui.get_io()
        io.set_ini_filename(None)  # no imgui.ini in the user's working folder (the editor keeps its own)
        self.windowed = window is not None
        if self.windowed:
            # our key callbacks are already set: the backend chains to them
            imgui.backends.glfw_init_for_vulkan(ctypes.cast(window, ctypes.c_void_p).value or 0, True)
        renderer = session.renderer
        self.renderer = ImGuiRenderer(session.device, session.gpu.target, len(renderer.frames.frames))
        renderer.overlay = self.renderer  # the renderer stays for the whole run: attached once
        self.scripted = ScriptedImGuiInput(imgui, self.windowed)
        self.build_ms = 0.0
        self.min_interval_s = 0.0 if not max_ui_hz else 1.0 / max_ui_hz
        self._last_build = -1e9
        self.builds = 0

    @property
    def cost_ms(self) -> float:
        """The UI's CPU time last frame: building it, copying its geometry, recording it."""
        return self.build_ms + self.renderer.cpu_ms

    def feed(self, events: Any) -> None:
        """An input script's events of this frame (action, *arguments), for the next UI built."""
        self.scripted.queue(events)

    @property
    def wants_keyboard(self) -> bool:
        return bool(self.imgui.get_io().want_capture_keyboard)

    @property
    def wants_mouse(self) -> bool:
        """The pointer is over a window of the UI, or a drag began on one."""
        return bool(self.imgui.get_io().want_capture_mouse)

    def build(self, world: World, stats: Any, perf: PerfMonitor, dt: float, width: int, height: int) -> None:
        """This frame's UI, up to imgui.render(); the renderer draws it after the tone map."""
        imgui = self.imgui
        t0 = time.perf_counter()
        if t0 - self._last_build < self.min_interval_s:
            self.build_ms = 0.0  # the renderer draws the last UI again
            return
        self._last_build = t0
        self.builds += 1
        if self.windowed:
            imgui.backends.glfw_new_frame()
        else:
            io = imgui.get_io()
            io.display_size = (float(width), float(height))
            io.delta_time = max(float(dt), 1e-6)
        self.scripted.flush()  # after the backend's events: the script's pointer wins
        imgui.new_frame()
        begun = imgui.internal.ErrorRecoveryState()
        imgui.internal.error_recovery_store_state(begun)
        try:
            self.draw(world, stats, perf)
        except Exception:
            self._recover(begun)  # the windows left open are closed: the next frame can begin
            raise
        finally:
            imgui.render()
        self.build_ms = (time.perf_counter() - t0) * 1e3

    def _recover(self, begun: Any) -> None:
        """End what a failed draw left begun (windows, IDs, ...), quietly: the error is raised."""
        io = self.imgui.get_io()
        flags = [f"config_error_recovery_enable_{what}" for what in ("assert", "debug_log", "tooltip")]
        kept = [getattr(io, flag) for flag in flags]
        for flag in flags:
            setattr(io, flag, False)
        try:
            self.imgui.internal.error_recovery_try_to_recover_state(begun)
        finally:
            for flag, value in zip(flags, kept, strict=True):
                setattr(io, flag, value)

    def draw(self, world: World, stats: Any, perf: PerfMonitor) -> None:
        """The windows (between new_frame and render)."""

    def take_requests(self) -> Settings | None:
        """Settings changes for the loop to apply (none by default)."""
        return None

    def in_force(self, settings: Settings) -> None:
        """What the session runs with after applying the requests."""

    def refused(self, message: str) -> None:
        """A request the session refused."""

    def scene_failed(self, scene: str, message: str) -> None:
        """`scene`, just opened, failed in its first frames; the one before it is back."""
        self.refused(message)

    def destroy(self) -> None:
        self.renderer.destroy()
        if self.windowed:
            self.imgui.backends.glfw_shutdown()
        self.implot.destroy_context(self.plot_context)
        self.imgui.destroy_context(self.context)
