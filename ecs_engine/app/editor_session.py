"""One run's editor: the ImGui session (imgui_session.py) with the editor and the Perf window.
The editor only produces requests: the run loop calls `EditorSession.build` before rendering
and hands `take_requests()` to `Session.apply` after."""

from __future__ import annotations

from typing import Any

from ..ecs.world import World
from ..render.frame.viewport import EditorViewport
from .editor import Editor, SceneStats
from .imgui_session import ImGuiSession
from .perf import PerfMonitor
from .perf_overlay import PerfOverlay
from .session import Session
from .settings import Settings


def scene_stats(world: World, stats: Any) -> SceneStats:
    if stats is None:
        return SceneStats(entities=len(world))
    return SceneStats(entities=len(world), visible=stats.instances, draws=stats.draws, triangles=stats.triangles)


class EditorSession(ImGuiSession):
    def __init__(
        self,
        session: Session,
        scenes: tuple[str, ...],
        max_threads: int,
        window: Any = None,
        max_ui_hz: float | None = 120.0,
    ) -> None:
        super().__init__(session, window, max_ui_hz)
        self.editor = Editor(session.settings, scenes, max_threads, session.device.ray_tracing is not None)
        self.editor.show_shadow_maps(session.renderer, self.renderer)
        self.scene_renderer = renderer = session.renderer  # draws the scene for the Scene window
        # the scene drawn into an image the Scene window shows (render/frame/viewport.py)
        renderer.viewport = self.viewport = EditorViewport(session.device)
        self.editor.show_scene(self.viewport, self.renderer, lambda: renderer.target)
        self.overlay = PerfOverlay()
        app = getattr(session, "app", None)  # an App's game (AppSession): its HUD floats over the editor too
        self.game_ui: list[Any] = list(app.ui) if app is not None else []
        session.on_world.append(lambda world: self.editor.forget_world())

    def draw(self, world: World, stats: Any, perf: PerfMonitor) -> None:
        self.editor.draw(world, scene_stats(world, stats))  # sets the viewport's size (or None)
        self.overlay.draw(perf, self.cost_ms)
        for draw in self.game_ui:
            draw(self.imgui, world)

    @property
    def scene(self) -> Any:
        """The Scene window (editor_viewport.py): the game's view, its `hovered` and `view()`."""
        return self.editor.scene

    def take_requests(self) -> Settings | None:
        """What the user changed in the editor since the last call, or None."""
        return self.editor.take_requests()

    def in_force(self, settings: Settings) -> None:
        self.editor.in_force(settings)

    def refused(self, message: str) -> None:
        self.editor.refused(message)

    def scene_failed(self, scene: str, message: str) -> None:
        self.editor.refused(message)
        self.editor.files.failed_after_opening(self.editor, scene, message)
