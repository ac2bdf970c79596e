"""The Session of an App (app.py) and its UI: the run loop's session whose world and schedule are
the App's, and the ImGui session that draws the App's HUD functions (and the Perf window).

The App's world is made once: the editor may switch to a demo scene or a scene file and back,
and the game is where it was. Without RenderPlugin the renderer is simulation.py's, which draws
nothing and needs no GPU.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from ..ecs.schedule import Schedule
from ..ecs.world import World
from ..render.assets.meshes import Meshes
from .imgui_session import ImGuiSession
from .perf import PerfMonitor
from .session import FrameSource, Session
from .settings import RunOptions, Settings


class AppSession(Session):
    def __init__(self, app: Any, options: RunOptions, source: FrameSource) -> None:
        """`app`: the App (app.py, which imports this module when it runs)."""
        self.app = app
        super().__init__(replace(options, scene=app.name), source)  # the App's world comes first

    def _make_renderer(self, start: Settings) -> Any:
        if not self.app.renders:
            from .simulation import SimulationRenderer

            return SimulationRenderer(start)
        return super()._make_renderer(start)

    def _build(self, scene: str, path: str | None) -> tuple[World, Schedule]:
        if scene == self.app.name:
            return self.app.open(self)
        return super()._build(scene, path)  # the editor's demo scenes and scene files

    def frame_done(self) -> None:
        super().frame_done()
        saves = self.app.scene_files
        if saves is not None and saves.pending:  # a system asked for a save: the frame's changes are in
            saves.flush()

    def close(self) -> None:
        self.app.close_hooks()
        self.app.window.unbind()
        meshes, gpu = self.app.world.resources.get(Meshes), getattr(self, "gpu", None)
        if meshes is not None and gpu is not None and meshes.registry is gpu.meshes:
            meshes.keep_on_cpu()  # the world outlives the run: it can still be saved
        super().close()


class AppUI(ImGuiSession):
    """The App's `add_ui` functions, built every frame (a HUD must follow the game), and the
    Perf window with PerfPlugin(overlay=True)."""

    def __init__(self, session: Session, window: Any = None) -> None:
        super().__init__(session, window, max_ui_hz=None)
        assert isinstance(session, AppSession)
        self.app = session.app
        self.rects: dict[str, tuple[float, float, float, float]] = {}
        self.overlay: Any = None
        if self.app.perf_overlay:
            from .perf_overlay import PerfOverlay

            self.overlay = PerfOverlay()

    def draw(self, world: World, stats: Any, perf: PerfMonitor) -> None:
        rects: dict[str, tuple[float, float, float, float]] = {}
        for draw in self.app.ui:
            drawn = draw(self.imgui, world)
            if isinstance(drawn, dict):
                rects.update(drawn)
        self.rects = rects
        if self.overlay is not None:
            self.overlay.draw(perf, self.cost_ms)
