"""`ecs-engine demo [SCENE] --print-graph`: the frame graph a scene and render configuration
build, printed after one frame (render/graph/describe.py: the passes in order with what each
reads and writes, the culled ones, the transients and imports). The frame is drawn headless
(an offscreen image: no window or display needed), so the graph is the one the renderer really
set up, not a plan; the other output of the run (perf lines, device line) is left out."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .settings import RunOptions

PRINT_GRAPH_HELP = (
    "draw one frame headless and print the frame graph it built (passes in order, what each reads "
    "and writes, culled passes, transients with format and size), then exit"
)


def frame_graph_text(renderer: Any) -> str:
    """The renderer's last frame's output graph as text (with several camera views: each view's,
    in drawing order: render/frame/views.py)."""
    views = getattr(renderer, "views", None)
    if views is not None and views.on:
        return views.describe() or "no frame graph was set up"
    outputs = renderer.output.graph
    text = outputs.describe() if outputs is not None else ""
    return text or "no frame graph was set up"


def print_graph(options: RunOptions) -> int:
    """Run `options` headless for one frame (or --frames), print the graph; 0, or 1 with
    validation messages (--validate)."""
    from .loop import run
    from .report import report_validation

    graphs: list[str] = []

    def keep_graph(session: Any) -> str:  # called while the session lives, after the frames
        graphs.append(frame_graph_text(session.renderer))
        return ""

    headless = replace(options, headless=True, frames=options.frames or 1, quiet=True, perf_lines=False)
    result = run(headless, log=lambda text: None, summary=keep_graph)
    print("\n".join(graphs))
    return report_validation(result)
