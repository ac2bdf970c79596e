"""The editor's panels at 1280x720 and a smaller window (issue 33): no label or button runs past
its window's edge (the Inspector's "scale" radio button was cut to "sc"), measured with ImGui's
own layout figures, not pixels: a window's content width (the furthest any item reached) is at
most the width of its content region, with every kind of entity selected and on the Materials tab."""

from __future__ import annotations

import pytest
from test_editor import Scene

from ecs_engine.components import Camera, DirectionalLight, Mesh, PointLight, SpotLight


def overflows(imgui, before: dict) -> dict[str, float]:
    """Pixels by which each window's items ran past its content region last frame (windows
    whose vertical scrollbar came or went that frame are skipped: ImGui lays them out again)."""
    found = {}
    for window in imgui.get_current_context().windows:
        if not window.was_active or window.hidden:
            continue
        region = window.content_region_rect
        over = window.content_size.x - (region.max.x - region.min.x)
        steady = before.get(window.name) == window.scrollbar_y
        before[window.name] = window.scrollbar_y
        if over > 0.5 and steady:
            found[window.name] = over
    return found


def build(scene) -> None:
    """The UI alone (its layout is all that is measured; the 1280x720 shadows scene takes seconds
    a frame on lavapipe)."""
    scene.session.build(scene.state.world, scene.stats, scene.perf, 1 / 60, *scene.size)


@pytest.mark.parametrize("size", [(1280, 720), (1024, 600)])
def test_every_label_and_button_of_the_editor_shows(size):
    from imgui_bundle import imgui

    scene = Scene("shadows", size=size)
    try:
        editor, world = scene.session.editor, scene.state.world
        before: dict = {}
        seen: dict[str, dict[str, float]] = {}
        scene.frame()  # drawn once: the shadow maps the light sections show exist
        for kind in (Mesh, PointLight, SpotLight, DirectionalLight, Camera):
            editor.selected = int(world.query(kind).entities()[0])
            for _ in range(3):
                build(scene)
                for name, over in overflows(imgui, before).items():
                    seen.setdefault(kind.__name__, {})[name] = over
        editor.open_tab = "Materials"
        for _ in range(3):
            build(scene)
            for name, over in overflows(imgui, before).items():
                seen.setdefault("Materials", {})[name] = over
        assert seen == {}
        inspector = imgui.internal.find_window_by_name("Inspector").content_region_rect
        for radio in ("translate", "rotate", "scale"):  # the gizmo's operations, "scale" was cut to "sc"
            x0, _, x1, _ = editor.rects[radio]
            assert inspector.min.x <= x0 and x1 <= inspector.max.x + 0.5, (radio, editor.rects[radio])
        scene.frame()  # the overlay draws what was built (and the teardown is checked as usual)
    finally:
        scene.close()
