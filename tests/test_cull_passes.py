"""The indirect path's compute as one frame graph pass per step (render/draw/cull_pass.py),
planned without a device: the steps in order, with and without occlusion culling, and the
barriers the graph places between them from their declarations, against the ones
indirect_draws.compute_barriers and occlusion_passes placed by hand before (issue 36)."""

from __future__ import annotations

from types import SimpleNamespace as NS

from test_frame_graph import Step

from ecs_engine.render.culling.occlusion_passes import OcclusionPasses
from ecs_engine.render.frame.scene_passes import ScenePasses
from ecs_engine.render.graph import FrameGraph

buffer = NS  # handle, size
FRUSTUM = ["cull.zero", "cull.frustum", "cull.compact", "cull.readback", "cull.host"]
OCCLUSION = [
    "cull.zero",
    "cull.early",
    "cull.early_compact",
    "occlusion.depth",
    "occlusion.pyramid",
    "cull.rezero",
    "cull.late",
    "cull.compact",
    "cull.readback",
    "cull.host",
]


def occlusion(fresh=False):
    o = NS(
        depth=NS(handle=80, view=81),
        pyramid=buffer(handle=82, size=4096),
        visibility=buffer(handle=83, size=4096),
        size=(32, 32),
        samples=1,
        fresh=fresh,
        depth_token=(1, 80),
    )
    o.import_into = lambda g: OcclusionPasses.import_into(o, g)
    o.imports = lambda: OcclusionPasses.imports(o)
    return o


def path(occlusion=None):
    draws = {n: buffer(handle=10 + i, size=64) for i, n in enumerate(("ids", "commands", "state", "readback"))}
    return NS(
        pending=True,
        compute=NS(occlusion=occlusion),
        draw_buffers=lambda slot: {f"draws.{n}": b for n, b in draws.items()},
    )


def graph(p):
    maps = NS(image=NS(handle=50, view=51), resolution=64, layers=1, layer_views=(60,))
    s = ScenePasses(None, NS(pass_=None), NS(cleared=True, maps=maps, gpu=None, gpu_culled=lambda b: b))
    s.begin(p, 0, NS(set_array=None, clusters=buffer(handle=9, size=128)), None, 0, [], [])
    g = FrameGraph(None)
    s.add_to(g)
    s.import_into(g)
    g.add_pass(Step("forward", lambda b: ([b.read(n, a) for n, a in s.reads], b.side_effect())))
    g.compile((32, 32))
    return g


def rows(g, name):
    return {b.resource: b for b in g.compiled.barriers.before[name]}


def test_the_frustum_steps_run_in_order_with_the_barriers_compute_barriers_placed():
    g = graph(path())
    assert g.order == [*FRUSTUM, "forward"]
    assert rows(g, "cull.zero") == {}  # the slot's buffers: their last frame's fence covered them
    zeroed = rows(g, "cull.frustum")["draws.state"]  # to_compute: the fill -> the cull
    assert (zeroed.src_stages, zeroed.src_access) == ({"TRANSFER"}, {"TRANSFER_WRITE"})
    assert zeroed.dst_stages == {"COMPUTE_SHADER"} and "SHADER_STORAGE_READ" in zeroed.dst_access
    counted = rows(g, "cull.compact")["draws.state"]  # compute_to_compute: cull -> compact
    assert counted.src_stages == {"COMPUTE_SHADER"} and "SHADER_STORAGE_WRITE" in counted.src_access
    assert counted.dst_stages == {"COMPUTE_SHADER"}
    copied = rows(g, "cull.readback")["draws.state"]  # to_copy: compact -> the counters' copy
    assert (copied.src_stages, copied.dst_stages) == ({"COMPUTE_SHADER"}, {"TRANSFER"})
    host = rows(g, "cull.host")["draws.readback"]  # to_host: the copy -> the host's read
    assert (host.src_stages, host.src_access) == ({"TRANSFER"}, {"TRANSFER_WRITE"})
    assert (host.dst_stages, host.dst_access) == ({"HOST"}, {"HOST_READ"})
    drawn = rows(g, "forward")  # to_draw: the commands, counts and ids -> the draws
    assert drawn["draws.commands"].dst_stages == {"DRAW_INDIRECT"}
    assert drawn["draws.state"].dst_stages == {"DRAW_INDIRECT"}
    assert drawn["draws.ids"].dst_stages == {"VERTEX_SHADER"}
    assert drawn["draws.commands"].src_stages == drawn["draws.ids"].src_stages == {"COMPUTE_SHADER"}
    assert "COMPUTE_SHADER" in drawn["draws.state"].src_stages  # (and the copy's read of it)


def test_the_occlusion_steps_run_in_order_with_every_barrier_between_them():
    g = graph(path(occlusion()))
    assert g.order == [*OCCLUSION, "forward"]
    assert rows(g, "cull.early")["draws.state"].src_stages == {"TRANSFER"}
    last_frame = rows(g, "cull.early")["occlusion.visibility"]  # the frame before's late cull
    assert last_frame.src_stages == {"COMPUTE_SHADER"} and last_frame.dst_stages == {"COMPUTE_SHADER"}
    assert rows(g, "cull.early_compact")["draws.state"].src_stages == {"COMPUTE_SHADER"}
    early = rows(g, "occlusion.depth")  # the early commands -> their draws; the depth cleared
    assert early["draws.commands"].dst_stages == {"DRAW_INDIRECT"}
    assert early["draws.ids"].dst_stages == {"VERTEX_SHADER"}
    assert early["occlusion.depth"].old_layout == "UNDEFINED"
    assert early["occlusion.depth"].new_layout == "DEPTH_STENCIL_ATTACHMENT_OPTIMAL"
    depth = rows(g, "occlusion.pyramid")["occlusion.depth"]  # end_depth's barrier by hand before
    assert depth.old_layout == "DEPTH_STENCIL_ATTACHMENT_OPTIMAL"
    assert depth.new_layout == "DEPTH_STENCIL_READ_ONLY_OPTIMAL"
    assert depth.dst_stages >= {"COMPUTE_SHADER"}
    assert rows(g, "occlusion.pyramid")["occlusion.pyramid"].src_stages == {"COMPUTE_SHADER"}  # the frame before
    again = rows(g, "cull.rezero")["draws.state"]  # drawn_to_compute: the early draws read the counts
    assert "DRAW_INDIRECT" in again.src_stages and again.dst_stages == {"TRANSFER"}
    late = rows(g, "cull.late")
    assert late["draws.state"].src_stages == {"TRANSFER"}  # the zeroed counters
    assert "VERTEX_SHADER" in late["draws.ids"].src_stages  # the early draws read the ids
    assert late["occlusion.pyramid"].src_stages == {"COMPUTE_SHADER"}
    assert "SHADER_STORAGE_WRITE" in late["occlusion.pyramid"].src_access
    assert late["occlusion.visibility"].src_stages == {"COMPUTE_SHADER"}  # after the early cull read it
    rewritten = rows(g, "cull.compact")["draws.commands"]  # the early draws read the commands
    assert "DRAW_INDIRECT" in rewritten.src_stages
    assert rows(g, "cull.host")["draws.readback"].dst_access == {"HOST_READ"}
    assert not [b for b in g.compiled.barriers.after if b.resource.startswith("occlusion.")]  # the depth is dropped


def test_a_new_visibility_buffer_is_zeroed_before_the_early_cull():
    g = graph(path(occlusion(fresh=True)))
    zeroed = rows(g, "cull.early")["occlusion.visibility"]
    assert (zeroed.src_stages, zeroed.src_access) == ({"TRANSFER"}, {"TRANSFER_WRITE"})
    assert rows(g, "cull.zero")["occlusion.visibility"].dst_stages == {"TRANSFER"}


def test_each_step_gets_at_most_one_barrier_batch_and_no_step_is_culled():
    for p, order in ((path(), FRUSTUM), (path(occlusion()), OCCLUSION)):
        g = graph(p)
        assert [n for n in g.order if n in order] == order
        culled = {n for n in g.culled if n.startswith(("cull.", "occlusion."))}
        assert culled == set(FRUSTUM + OCCLUSION) - set(order)
        assert all(b.resource != "draws.keys" for name in order for b in g.compiled.barriers.before[name])


def test_the_steps_are_timed_under_the_names_the_one_pass_had():
    """The perf log and monitor add up a name's spans: "culling (compute)" and "light clusters"
    stay comparable with the frames before the split."""
    from ecs_engine.render.frame.scene_passes import MARKS

    g = graph(path(occlusion()))
    culled = [n for n in g.order if n.startswith(("cull.", "occlusion."))]
    assert {MARKS[n] for n in culled} == {"culling (compute)"}
    clusters = [n for n in MARKS if n.startswith("light_clusters.")]
    assert len(clusters) == 3 and {MARKS[n] for n in clusters} == {"light clusters"}
