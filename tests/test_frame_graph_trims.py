"""Barriers the frame graph leaves out, planned without a device: an import read in the layout
it came in (the shadow maps a second camera's graph only samples, the layers no view drew this
frame) waits for nothing before and needs no barrier after; what a layout or a write needs
stays (render/graph/barriers.py)."""

from __future__ import annotations

from test_frame_graph import Step

from ecs_engine.render.graph import Access, FrameGraph, Load

READ = "DEPTH_STENCIL_READ_ONLY_OPTIMAL"
STAGES = ("FRAGMENT_SHADER", "COMPUTE_SHADER", "EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS")


def maps_graph(*steps, after=READ):
    """The shadow maps as maps_graph.py imports them (two layers), then `steps` (name, setup)."""
    g = FrameGraph(None)
    g.import_image(
        "maps",
        handle=1,
        view=2,
        format="VK_FORMAT_D32_SFLOAT",
        extent=(32, 32),
        layers=2,
        layer_views=(3, 4),
        layout_before=READ,
        layout_after=after,
        stage_before=STAGES,
    )
    for name, setup in steps:
        g.add_pass(Step(name, setup))
    g.compile((32, 32))
    return g


def sample(access=Access.DEPTH_SAMPLED):
    return lambda b: (b.read("maps", access), b.side_effect())


def draw(layer):
    return lambda b: (b.write("maps", Access.DEPTH_WRITE, layer=layer, load=Load.CLEAR, region=True), b.side_effect())


def count(g):
    plan = g.compiled.barriers
    return sum(len(rows) for rows in plan.before.values()) + len(plan.after)


def test_an_import_only_read_in_its_layout_has_no_barrier_before_or_after():
    g = maps_graph(("forward", sample()), ("lighting", sample()))
    assert g.compiled.barriers.before == {"forward": [], "lighting": []}
    assert g.compiled.barriers.after == []
    assert "barrier" not in g.describe()


def test_reads_in_other_stages_of_an_untouched_import_need_no_barrier_between_them():
    g = maps_graph(("rays", sample(Access.RAY_SAMPLED)), ("forward", sample()), after="SHADER_READ_ONLY_OPTIMAL")
    (first,) = g.compiled.barriers.before["rays"]  # another layout: a transition, after stage_before
    assert (first.old_layout, first.new_layout) == (READ, "SHADER_READ_ONLY_OPTIMAL")
    assert first.src_stages == set(STAGES) and first.src_access == {"MEMORY_WRITE"}
    (back,) = g.compiled.barriers.before["forward"]  # and back: the transition made visible
    assert (back.old_layout, back.new_layout) == ("SHADER_READ_ONLY_OPTIMAL", READ)
    (last,) = g.compiled.barriers.after
    assert (last.old_layout, last.new_layout) == (READ, "SHADER_READ_ONLY_OPTIMAL")
    g = maps_graph(("sampled", sample()), ("tested", sample(Access.DEPTH_READ)))  # shaders, then depth tests
    assert count(g) == 0


def test_layers_drawn_get_their_barriers_and_the_kept_layers_none():
    g = maps_graph(("shadow_maps", draw(1)), ("forward", sample()), ("transparent", sample()))
    plan = g.compiled.barriers
    (to_draw,) = plan.before["shadow_maps"]
    assert (to_draw.base_layer, to_draw.layer_count, to_draw.old_layout) == (1, 1, READ)
    assert to_draw.src_stages == set(STAGES)  # the last frame's readers and depth tests
    (to_read,) = plan.before["forward"]  # layer 0 was not drawn: only layer 1 is made visible
    assert (to_read.base_layer, to_read.old_layout) == (1, "DEPTH_STENCIL_ATTACHMENT_OPTIMAL")
    assert plan.before["transparent"] == []  # a read after a read in the same layout
    (after,) = plan.after  # the drawn layer's write made visible to what follows the graph
    assert (after.base_layer, after.layer_count) == (1, 1) and "DEPTH_STENCIL_ATTACHMENT_WRITE" in after.src_access
    assert count(g) == 3


def test_a_write_after_an_untouched_import_is_read_still_waits():
    g = maps_graph(("forward", sample()), ("shadow_maps", draw(0)), ("late", sample()))
    plan = g.compiled.barriers
    assert plan.before["forward"] == []
    (to_draw,) = plan.before["shadow_maps"]  # after this frame's reads and the last frame's work
    assert to_draw.src_stages == set(STAGES) | {"RAY_TRACING_SHADER_BIT_KHR"}
    assert to_draw.src_access == {"MEMORY_WRITE"} and to_draw.old_layout == READ
    (to_read,) = plan.before["late"]
    assert to_read.base_layer == 0 and "DEPTH_STENCIL_ATTACHMENT_WRITE" in to_read.src_access


def test_an_import_read_in_its_layout_but_left_in_another_goes_there_after():
    g = maps_graph(("forward", sample()), after="SHADER_READ_ONLY_OPTIMAL")
    assert g.compiled.barriers.before["forward"] == []
    (after,) = g.compiled.barriers.after
    assert (after.old_layout, after.new_layout, after.layer_count) == (READ, "SHADER_READ_ONLY_OPTIMAL", 2)
