"""Imported buffers (a frame slot's, imported again each frame): the first use waits for earlier
work, a write then a read in another pass gets a buffer barrier, and `visible_after` makes the
last writes visible to commands recorded after the graph (a consumer still outside it). Planned
without a device."""

from __future__ import annotations

from test_frame_graph import Step

from ecs_engine.render.graph import Access, FrameGraph


def clusters_graph(visible_after):
    g = FrameGraph(None)
    g.import_buffer("clusters", handle=7, size=256, visible_after=visible_after)

    def fill(b):
        b.write("clusters", Access.TRANSFER_WRITE)
        b.write("clusters", Access.COMPUTE_READ_WRITE)
        b.side_effect()

    g.add_pass(Step("light_clusters", fill))
    g.compile((8, 8))
    return g


def test_a_buffer_made_visible_after_the_graph_gets_a_final_barrier_from_its_last_writes():
    plan = clusters_graph(True).compiled.barriers
    (first,) = plan.before["light_clusters"]
    assert first.src_stages == {"ALL_COMMANDS"}  # the frame slot's earlier use, whatever it was
    assert first.dst_stages == {"TRANSFER", "COMPUTE_SHADER"} and first.base_mip is None
    (after,) = plan.after
    assert after.resource == "clusters" and after.base_mip is None
    assert after.src_stages == {"TRANSFER", "COMPUTE_SHADER"}
    assert after.src_access >= {"TRANSFER_WRITE", "SHADER_STORAGE_WRITE"}
    assert after.dst_stages == {"ALL_COMMANDS"} and after.dst_access == {"MEMORY_READ", "MEMORY_WRITE"}
    assert "after: barrier clusters (COMPUTE_SHADER|TRANSFER -> ALL_COMMANDS)" in clusters_graph(True).describe()


def test_without_visible_after_a_buffer_has_no_final_barrier_and_the_flag_recompiles():
    g = clusters_graph(False)
    assert g.compiled.barriers.after == []
    compiles = g.compiles
    g.import_buffer("clusters", handle=8, size=256)  # another slot's buffer: same plan
    g.compile((8, 8))
    assert g.compiles == compiles
    g.import_buffer("clusters", handle=8, size=256, visible_after=True)
    g.compile((8, 8))
    assert g.compiles == compiles + 1 and len(g.compiled.barriers.after) == 1


def test_a_read_of_the_buffer_in_a_later_pass_waits_for_the_writes():
    g = clusters_graph(False)
    g.add_pass(Step("forward", lambda b: (b.read("clusters", Access.FRAGMENT_READ), b.side_effect())))
    g.compile((8, 8))
    (row,) = g.compiled.barriers.before["forward"]
    assert row.src_stages == {"TRANSFER", "COMPUTE_SHADER"} and "FRAGMENT_SHADER" in row.dst_stages


def test_a_fenced_buffer_has_no_first_barrier_but_its_readers_still_wait():
    g = FrameGraph(None)
    g.import_buffer("draws", handle=3, size=64, stage_before="NONE")  # the frame slot's last use was fenced

    def cull(b):
        b.write("draws", Access.COMPUTE_READ_WRITE)
        b.side_effect()

    g.add_pass(Step("cull", cull))
    g.add_pass(Step("forward", lambda b: (b.read("draws", Access.INDIRECT_READ), b.side_effect())))
    g.compile((8, 8))
    plan = g.compiled.barriers
    assert plan.before["cull"] == []  # nothing in flight to wait for
    (row,) = plan.before["forward"]
    assert row.src_stages == {"COMPUTE_SHADER"} and row.dst_stages == {"DRAW_INDIRECT"}
