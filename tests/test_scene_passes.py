"""The scene's passes ahead of the output's forward (render/frame/scene_passes.py: the indirect
path's "cull.*" steps, the "light_clusters.*" ones, "shadow_maps") planned without a device: what they declare from
the frame's inputs, and the barriers the graph places between them and a forward pass that
declares their `reads` (the ones the hand barriers made before)."""

from __future__ import annotations

from types import SimpleNamespace as NS

from test_frame_graph import Step

from ecs_engine.render.frame.scene_passes import ScenePasses
from ecs_engine.render.graph import FrameGraph

buffer = NS  # handle, size
CULL = ["cull.zero", "cull.frustum", "cull.compact", "cull.readback", "cull.host"]  # the frustum's steps
CLUSTERS = ["light_clusters.zero", "light_clusters.bounds", "light_clusters.tiles"]


def scene(cleared=True, gpu=None):
    maps = NS(image=NS(handle=50, view=51), resolution=64, layers=3, layer_views=(60, 61, 62))
    shadows = NS(cleared=cleared, maps=maps, gpu=gpu, gpu_culled=lambda secondaries: secondaries)
    return ScenePasses(None, NS(pass_=None), shadows)


def indirect(pending=True):
    draws = {n: buffer(handle=10 + i, size=64) for i, n in enumerate(("ids", "commands", "state", "readback"))}
    return NS(pending=() if pending else None, draw_buffers=lambda slot: {f"draws.{n}": b for n, b in draws.items()})


def graph(s, frame_views, grid=True, path=None):
    s.begin(
        path or indirect(),
        0,
        NS(set_array=None, clusters=buffer(handle=9, size=128)),
        NS(tiles_x=2, tiles_y=2) if grid else None,
        3,
        frame_views,
        [[] for _ in frame_views],
    )
    g = FrameGraph(None)
    s.add_to(g)
    s.import_into(g)
    g.add_pass(Step("forward", lambda b: ([b.read(n, a) for n, a in s.reads], b.side_effect())))
    g.compile((32, 32))
    return g


def test_forward_waits_for_the_cull_the_clusters_and_the_drawn_layers():
    g = graph(scene(), [NS(layer=1, resolution=32)])
    assert g.order == [*CULL, *CLUSTERS, "shadow_maps", "forward"]
    rows = {(b.resource, b.base_layer): b for b in g.compiled.barriers.before["forward"]}
    assert rows[("clusters", 0)].src_stages == {"COMPUTE_SHADER"}  # the fills' were waited for by the dispatches
    assert rows[("clusters", 0)].dst_stages == {"FRAGMENT_SHADER"}
    assert rows[("draws.commands", 0)].dst_stages == {"DRAW_INDIRECT"}
    assert rows[("draws.ids", 0)].dst_stages == {"VERTEX_SHADER"}
    drawn = rows[("shadow_maps", 1)]  # the drawn layer: from the attachment layout to sampling
    assert (drawn.old_layout, drawn.new_layout) == (
        "DEPTH_STENCIL_ATTACHMENT_OPTIMAL",
        "DEPTH_STENCIL_READ_ONLY_OPTIMAL",
    )
    (write,) = g.compiled.barriers.before["shadow_maps"]  # its corner, kept: from the sampled layout
    assert (write.base_layer, write.layer_count, write.old_layout) == (1, 1, "DEPTH_STENCIL_READ_ONLY_OPTIMAL")
    assert "FRAGMENT_SHADER" in write.src_stages  # after the frame before's lighting read it


def test_passes_without_work_declare_nothing_and_are_culled():
    """A frame without views, light clusters or GPU-culled draws runs forward alone: the maps
    were cleared when made (gpu/shadow_maps.py), so no first frame declares anything else."""
    assert graph(scene(), [], grid=False, path=indirect(pending=False)).order == ["forward"]
    g = graph(scene(), [], grid=False, path=indirect(pending=False))
    assert set(g.culled) >= {*CULL, *CLUSTERS, "shadow_cull", "shadow_maps"}


def test_the_views_culled_on_the_gpu_are_drawn_after_their_compute():
    names = [f"shadow_draws.0.{n}" for n in ("ids", "state", "commands")] + ["shadow_draws.readback"]
    gpu = NS(draw_buffers=lambda: {n: buffer(handle=70 + i, size=32) for i, n in enumerate(names)})
    g = graph(scene(gpu=gpu), [NS(layer=0, resolution=64)])
    assert g.order == [*CULL, *CLUSTERS, "shadow_cull", "shadow_maps", "forward"]
    rows = {b.resource: b for b in g.compiled.barriers.before["shadow_maps"]}
    assert rows["shadow_draws.0.commands"].src_stages == {"COMPUTE_SHADER"}
    assert rows["shadow_draws.0.commands"].dst_stages == {"DRAW_INDIRECT"}
    assert rows["shadow_draws.0.state"].dst_stages == {"DRAW_INDIRECT"}
    assert rows["shadow_draws.0.ids"].dst_stages == {"VERTEX_SHADER"}


def test_the_frame_slots_buffers_are_not_waited_for_at_their_first_use():
    g = graph(scene(), [])
    firsts = {b.resource for name in ("cull.zero", "light_clusters.zero") for b in g.compiled.barriers.before[name]}
    assert not firsts & {"clusters", "draws.ids", "draws.commands", "draws.state", "draws.readback"}


def test_the_light_cluster_steps_get_the_barriers_placed_by_hand_before():
    """light_clusters.zero fills, .bounds and .tiles dispatch: transfer -> compute, then compute
    -> compute between the two dispatches (ClusterPass's two hand barriers before issue 36)."""
    g = graph(scene(), [])
    assert g.compiled.barriers.before["light_clusters.zero"] == []  # the slot's: fenced
    (filled,) = g.compiled.barriers.before["light_clusters.bounds"]
    assert (filled.resource, filled.src_stages, filled.src_access) == ("clusters", {"TRANSFER"}, {"TRANSFER_WRITE"})
    assert filled.dst_stages == {"COMPUTE_SHADER"}
    (bounded,) = g.compiled.barriers.before["light_clusters.tiles"]
    assert (bounded.src_stages, bounded.dst_stages) == ({"COMPUTE_SHADER"}, {"COMPUTE_SHADER"})
    assert "SHADER_STORAGE_WRITE" in bounded.src_access and "SHADER_STORAGE_READ" in bounded.dst_access


def test_a_frame_with_nothing_to_do_brings_back_its_slots_state_and_no_stale_one():
    s, path = scene(), indirect(pending=False)  # culls on the CPU: nothing for the cull steps
    frames = [NS(set_array=i, clusters=buffer(handle=20 + i, size=128), set_version=1) for i in range(2)]

    def begin_slot(slot, views=()):
        s.begin_slot(path, slot, frames[slot], None, 3, list(views))
        return s.signature()

    first, second = begin_slot(0), begin_slot(1)
    assert s.buffers == {"clusters": frames[1].clusters} and first != second
    assert begin_slot(0) is first and s.buffers == {"clusters": frames[0].clusters}  # brought back, not made
    assert s.clusters.grid is None  # idle: a recorded frame's `begin` names the slot's set
    drawn = begin_slot(0, [NS(layer=1, resolution=32)])  # a frame with a shadow map: the state changes
    assert s.shadows.views and drawn != first
    assert begin_slot(0) == first and not s.shadows.views  # made again: the views' state is not kept
    frames[0].clusters = buffer(handle=30, size=256)  # the slot's buffer grown, its set written anew
    frames[0].set_version += 1
    assert begin_slot(0) != first and s.signature()[2] == (("clusters", frames[0].clusters, 30),)
    s.begin(path, 0, frames[0], None, 3, [NS(layer=2, resolution=32)], [[]])  # a recorded frame's state
    begin_slot(0)
    assert not s.shadows.views  # after a recorded frame's state: made again
