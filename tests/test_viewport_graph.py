"""The editor viewport's output graph planned without a device (render/passes/output_graph.py,
output_frame.py): with a window image the UI samples "target" and draws "window", which the
graph outputs and the readback reads; the scene passes are kept because the UI reads them."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
import vulkan as vk

from ecs_engine.render.config import Form
from ecs_engine.render.passes.output_frame import WindowImage
from ecs_engine.render.passes.output_graph import OutputGraph

SRGB = vk.VK_FORMAT_R8G8B8A8_SRGB


def planned(window: bool, form: Form = Form.HDR):
    target = SimpleNamespace(
        color_format=SRGB,
        final_layout=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL if window else vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
    )
    device = SimpleNamespace(vk=vk) if form != Form.DIRECT else None  # no transients to make then
    output = SimpleNamespace(device=device, vk=vk, scene=None, clear_color=(0.1, 0.2, 0.3), target=target)
    og = OutputGraph(output, [])
    og.frame.overlay = object()
    og.frame.window = (
        WindowImage(101, 102, SRGB, (1024, 720), vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL) if window else None
    )
    graph = og._make(form, 1, SRGB, False, False, None)
    og._extent = (400, 300)
    image = SimpleNamespace(handle=7, view=8, format=vk.VK_FORMAT_R16G16B16A16_SFLOAT, width=1024, height=720)
    depth = SimpleNamespace(handle=9, view=10, format=vk.VK_FORMAT_D32_SFLOAT, width=1024, height=720)
    og._import_attachments(graph, form, SimpleNamespace(images=[depth, image], samples=1))
    og._import_target(graph, SimpleNamespace(image=5, view=6), (400, 300))
    if window:
        og._import_window(graph, og.frame.window)
    og._place_readback(graph, True)
    graph.compile((400, 300))
    return graph


def barriers(graph, name):
    return {b.resource: (b.old_layout, b.new_layout) for b in graph.compiled.barriers.before[name]}


def order(graph):
    """The compiled passes in order (describe's numbered lines): the culled are not there."""
    lines = [line.split() for line in graph.describe().splitlines()]
    return [w[1] for w in lines if len(w) >= 2 and w[0].isdigit()]


@pytest.mark.parametrize("form", [Form.HDR, Form.DIRECT])
def test_the_ui_samples_the_viewport_and_draws_the_window(form):
    graph = planned(True, form)
    scene = ["forward", "tone_map"] if form == Form.HDR else ["forward"]
    assert order(graph) == [*scene, "imgui", "readback"]  # kept: the UI reads what they draw
    assert barriers(graph, "imgui") == {
        "target": ("COLOR_ATTACHMENT_OPTIMAL", "SHADER_READ_ONLY_OPTIMAL"),
        "window": ("UNDEFINED", "COLOR_ATTACHMENT_OPTIMAL"),  # cleared by the UI's rendering
    }
    assert barriers(graph, "readback") == {"window": ("COLOR_ATTACHMENT_OPTIMAL", "TRANSFER_SRC_OPTIMAL")}
    imports = graph.describe()
    assert "imported target: R8G8B8A8_SRGB 400x300, UNDEFINED -> SHADER_READ_ONLY_OPTIMAL" in imports
    assert "imported window: R8G8B8A8_SRGB 1024x720, UNDEFINED after" in imports


def test_the_viewport_waits_for_the_last_frame_that_sampled_it():
    """Frame N+1's tone map overwrites what frame N's UI sampled: its first barrier waits for
    every stage, not just colour output and transfer."""
    graph = planned(True)
    (first,) = [b for b in graph.compiled.barriers.before["tone_map"] if b.resource == "target"]
    assert first.src_stages == {"ALL_COMMANDS"}


def test_the_scene_attachments_are_imported_at_the_viewport_size():
    described = planned(True).describe()
    assert "imported hdr: R16G16B16A16_SFLOAT 400x300" in described
    assert "imported depth: D32_SFLOAT 400x300" in described


def test_without_a_window_the_ui_draws_over_the_target():
    graph = planned(False)
    assert order(graph) == ["forward", "tone_map", "imgui", "readback"]
    assert "window" not in graph.describe()
    assert barriers(graph, "readback") == {"target": ("COLOR_ATTACHMENT_OPTIMAL", "TRANSFER_SRC_OPTIMAL")}


def test_the_pointer_is_measured_from_the_games_view():
    """In the editor the game's view is the Scene window (InputState.view): a game's pointer is
    measured from its corner, and its size is the view's (the mouse stays the window's)."""
    from ecs_engine.systems import ActionMap, InputState

    state = InputState(mouse=(350.0, 120.0), viewport=(1280.0, 720.0))
    actions = ActionMap({}, state)
    assert actions.pointer() == (350.0, 120.0) and state.in_view() == ((350.0, 120.0), (1280.0, 720.0))
    state.view = (300.0, 20.0, 677.0, 483.0)
    assert actions.pointer() == (50.0, 100.0)
    assert state.in_view() == ((50.0, 100.0), (677.0, 483.0))
    assert state.mouse == (350.0, 120.0)
