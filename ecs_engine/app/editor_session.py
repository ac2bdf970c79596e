"""One run's ImGui: the context, the Vulkan renderer for it, the editor and the Perf window,
and the code that applies the editor's requests (rebuilding what a setting needs).

The frame loops (app.run headless, window.run_windowed) hold a `SceneState` and call
`EditorSession.build` before rendering and `EditorSession.apply_requests` after.

The UI is rebuilt at most `max_ui_hz` times a second (default 120, a fast monitor's refresh);
frames in between draw the last UI again. A scene running at 2,000 FPS would otherwise spend
~0.2-0.3 ms of every frame rebuilding windows nobody can see change that fast; input waits in
ImGui's queue for at most one UI period.
"""

from __future__ import annotations

import ctypes
import time
from dataclasses import dataclass, replace
from typing import Any

from .editor import Editor, RenderSettings, SceneStats
from ..render.imgui_pass import ImGuiRenderer
from .perf import PerfMonitor
from .perf_overlay import PerfOverlay


@dataclass
class SceneState:
    """What the loop renders; replaced pieces are swapped in place by `apply_requests`."""

    options: Any  # app.RunOptions
    world: Any
    schedule: Any
    renderer: Any
    jobs: Any
    device: Any
    target: Any  # OffscreenTarget or Swapchain
    meshes: Any


def scene_stats(world: Any, stats: Any) -> SceneStats:
    if stats is None:
        return SceneStats(entities=sum(t.count for t in world.tables))
    return SceneStats(entities=sum(t.count for t in world.tables), visible=stats.instances, draws=stats.draws,
                      triangles=stats.triangles)


class EditorSession:
    def __init__(self, state: SceneState, scenes: tuple[str, ...], max_threads: int, frames_in_flight: int,
                 window: Any = None, max_ui_hz: float | None = 120.0) -> None:
        from imgui_bundle import imgui, implot

        self.imgui, self.implot = imgui, implot
        self.context = imgui.create_context()
        self.plot_context = implot.create_context()
        io = imgui.get_io()
        io.set_ini_filename(None)  # no imgui.ini in the user's working folder
        self.windowed = window is not None
        if self.windowed:
            # our key callbacks are already set: the backend chains to them
            imgui.backends.glfw_init_for_vulkan(ctypes.cast(window, ctypes.c_void_p).value, True)
        self.renderer = ImGuiRenderer(state.device, state.target.render_pass, 1, frames_in_flight)
        o = state.options
        present = getattr(o, "present", None) if self.windowed else None
        self.editor = Editor(RenderSettings(o.scene, o.mode, state.renderer.recorder, state.jobs.threads, o.culling,
                                            present), scenes, max_threads)
        self.overlay = PerfOverlay()
        self.build_ms = 0.0
        self.min_interval_s = 0.0 if not max_ui_hz else 1.0 / max_ui_hz
        self._last_build = -1e9
        self.builds = 0
        state.renderer.overlay = self.renderer

    @property
    def cost_ms(self) -> float:
        """The UI's CPU time last frame: building it, copying its geometry, recording it."""
        return self.build_ms + self.renderer.cpu_ms

    @property
    def wants_keyboard(self) -> bool:
        return bool(self.imgui.get_io().want_capture_keyboard)

    def build(self, state: SceneState, stats: Any, perf: PerfMonitor, dt: float, width: int, height: int) -> None:
        """This frame's UI, up to imgui.render(); the renderer draws it in the overlay subpass."""
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
        imgui.new_frame()
        self.editor.draw(state.world, scene_stats(state.world, stats))
        self.overlay.draw(perf, self.cost_ms)
        imgui.render()
        self.build_ms = (time.perf_counter() - t0) * 1e3

    def apply_requests(self, state: SceneState, swapchain: Any = None) -> bool:
        """Apply what the user changed in the editor; True when the renderer was replaced."""
        req = self.editor.take_requests()
        if req is None:
            return False
        from .run import build_scene, scene_builder
        from ..jobs import JobPool
        from ..render.renderer import Renderer

        o = state.options
        rebuilt = False
        if req.threads != state.jobs.threads:
            state.device.wait_idle()
            state.jobs.close()
            state.jobs = JobPool(req.threads)
            state.world.resources[JobPool] = state.jobs
            state.renderer.jobs = state.jobs
            o.threads = req.threads
        if req.present is not None and swapchain is not None and req.present != o.present:
            swapchain.set_present(req.present)
            o.present = req.present
        if req.scene != o.scene:
            state.renderer.destroy()
            state.options = o = replace(o, scene=req.scene, path=None, mode=req.mode, recorder=req.recorder,
                                        culling=req.culling)
            build = scene_builder(o.scene, o.entities)
            state.world, state.schedule, state.renderer = build_scene(o, build, state.device, state.target,
                                                                      state.meshes, state.jobs)
            self.editor.selected = None
            rebuilt = True
        elif req.mode != state.renderer.mode or (req.mode != "indirect" and req.recorder != state.renderer.recorder):
            state.renderer.set_path(req.mode, req.recorder)
            o.mode, o.recorder = req.mode, req.recorder
        state.renderer.culling = o.culling = req.culling
        state.renderer.overlay = self.renderer
        return rebuilt

    def destroy(self) -> None:
        self.renderer.destroy()
        if self.windowed:
            self.imgui.backends.glfw_shutdown()
        self.implot.destroy_context(self.plot_context)
        self.imgui.destroy_context(self.context)
