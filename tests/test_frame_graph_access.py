"""The frame graph's accesses for depth sampled by shaders, storage reads in fragment and vertex
shaders, ray tracing, acceleration structures and host readback: their barriers planned without
a device, and on lavapipe (no ray tracing there: those stages are left out when recorded)."""

from __future__ import annotations

import numpy as np
import test_frame_graph_gpu as gpu
from test_frame_graph import make
from test_frame_graph_gpu import RECT, Depth, H, W, layers

from ecs_engine.render.graph import Access, BufferDesc, ImageDesc, Load, Pass
from ecs_engine.render.graph.access import RAY_SHADERS

DEPTH = ImageDesc(format="VK_FORMAT_D32_SFLOAT")
run = gpu.run  # the fixture: a graph of passes executed on the shared device, read back


def test_depth_written_then_sampled_goes_read_only_for_every_shader_stage():
    g = make(
        ("shadow", lambda b: (b.create("z", DEPTH), b.write("z", Access.DEPTH_WRITE, load=Load.CLEAR))),
        ("light", lambda b: (b.read("z", Access.DEPTH_SAMPLED), b.side_effect())),
    )
    (row,) = g.compiled.barriers.before["light"]
    assert (row.old_layout, row.new_layout) == ("DEPTH_STENCIL_ATTACHMENT_OPTIMAL", "DEPTH_STENCIL_READ_ONLY_OPTIMAL")
    assert row.src_stages == {"EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"}
    assert row.src_access == {"DEPTH_STENCIL_ATTACHMENT_READ", "DEPTH_STENCIL_ATTACHMENT_WRITE"}
    assert row.dst_stages == {"FRAGMENT_SHADER", "COMPUTE_SHADER", RAY_SHADERS}
    assert row.dst_access == {"SHADER_SAMPLED_READ"}
    assert g.compiled.structure.usage["z"] == {"DEPTH_STENCIL_ATTACHMENT", "SAMPLED"}


def test_storage_reads_in_fragment_and_vertex_shaders_wait_for_the_compute_write():
    def cull(b):
        b.create("ids", BufferDesc(256))
        b.write("ids", Access.COMPUTE_WRITE)

    g = make(
        ("cull", cull),
        ("draw", lambda b: (b.read("ids", Access.VERTEX_STORAGE_READ), b.side_effect())),
        ("shade", lambda b: (b.read("ids", Access.FRAGMENT_READ), b.side_effect())),
    )
    (to_vertex,) = g.compiled.barriers.before["draw"]
    assert to_vertex.src_access == {"SHADER_STORAGE_WRITE"} and to_vertex.dst_stages == {"VERTEX_SHADER"}
    (to_fragment,) = g.compiled.barriers.before["shade"]  # another stage: made visible again
    assert to_fragment.dst_stages == {"FRAGMENT_SHADER"} and to_fragment.dst_access == {"SHADER_STORAGE_READ"}


def test_rays_write_storage_and_acceleration_structures_are_built_before_traced():
    def build(b):
        b.create("tlas", BufferDesc(1024))
        b.write("tlas", Access.AS_BUILD)

    def trace(b):
        b.create("mask", ImageDesc(format="VK_FORMAT_R8_UNORM"))
        b.read("tlas", Access.AS_READ)
        b.write("mask", Access.RAY_WRITE)

    g = make(
        ("build", build), ("trace", trace), ("use", lambda b: (b.read("mask", Access.RAY_SAMPLED), b.side_effect()))
    )
    tlas, mask = g.compiled.barriers.before["trace"]
    assert tlas.src_stages == {"ACCELERATION_STRUCTURE_BUILD_BIT_KHR"}
    assert tlas.dst_access == {"ACCELERATION_STRUCTURE_READ_BIT_KHR"} and RAY_SHADERS in tlas.dst_stages
    assert mask.new_layout == "GENERAL"
    (sampled,) = g.compiled.barriers.before["use"]
    assert (sampled.old_layout, sampled.new_layout) == ("GENERAL", "SHADER_READ_ONLY_OPTIMAL")
    assert sampled.src_stages == sampled.dst_stages == {RAY_SHADERS}


def test_host_read_is_a_buffer_access_made_visible_after_the_copy():
    g = make(
        ("clear", lambda b: (b.create("x", ImageDesc()), b.write("x", Access.COLOR_WRITE, load=Load.CLEAR))),
        (
            "copy",
            lambda b: (
                b.create("out", BufferDesc(64)),
                b.read("x", Access.TRANSFER_READ),
                b.write("out", Access.TRANSFER_WRITE),
            ),
        ),
        ("host", lambda b: (b.read("out", Access.HOST_READ), b.side_effect())),
    )
    (row,) = g.compiled.barriers.before["host"]
    assert (row.src_stages, row.src_access) == ({"TRANSFER"}, {"TRANSFER_WRITE"})
    assert (row.dst_stages, row.dst_access) == ({"HOST"}, {"HOST_READ"})
    import pytest

    from ecs_engine.errors import UsageError

    with pytest.raises(UsageError, match="image 'x' as HOST_READ, a buffer access"):
        make(
            ("clear", lambda b: (b.create("x", ImageDesc()), b.write("x", Access.COLOR_WRITE))),
            ("h", lambda b: (b.read("x", Access.HOST_READ), b.side_effect())),
        )


class SampleDepth(Pass):
    """Declares the depth sampled (a shader would bind it in DEPTH_STENCIL_READ_ONLY_OPTIMAL);
    records nothing: the graph's barriers are what is tested."""

    name = "sample"

    def setup(self, b):
        b.read("z", Access.DEPTH_SAMPLED)
        b.side_effect()

    def record(self, cb, ctx):
        pass


class CopyDepthOut(Pass):
    """Copies the depth into "out"; a later pass declares the host's read (no host barrier here)."""

    name = "copy"

    def setup(self, b):
        b.read("z", Access.TRANSFER_READ)
        b.write("out", Access.TRANSFER_WRITE)

    def record(self, cb, ctx):
        vk = ctx.vk
        region = vk.VkBufferImageCopy(
            imageSubresource=layers(vk, 0, vk.VK_IMAGE_ASPECT_DEPTH_BIT), imageExtent=vk.VkExtent3D(W, H, 1)
        )
        image, out = ctx.image("z").handle, ctx.buffer("out").handle
        vk.vkCmdCopyImageToBuffer(cb, image, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, out, 1, [region])


class HostRead(Pass):
    name = "host"

    def setup(self, b):
        b.read("out", Access.HOST_READ)
        b.side_effect()

    def record(self, cb, ctx):
        pass


def test_depth_sampled_and_read_by_the_host_on_a_device(run):
    graph, raw = run([Depth(), SampleDepth(), CopyDepthOut(), HostRead()], shape=(H, W, 2))
    depth = raw.view(np.float32)[..., 0]
    expected = np.full((H, W), 0.25, np.float32)
    x, y, w, h = RECT
    expected[y : y + h, x : x + w] = 0.75
    np.testing.assert_array_equal(depth, expected)
    assert graph.order == ["depth", "sample", "copy", "host"]
    (sampled,) = graph.compiled.barriers.before["sample"]
    assert sampled.new_layout == "DEPTH_STENCIL_READ_ONLY_OPTIMAL" and RAY_SHADERS in sampled.dst_stages
    (host,) = graph.compiled.barriers.before["host"]
    assert host.dst_stages == {"HOST"}


def test_ray_tracing_stages_are_left_out_where_the_device_has_none():
    from ecs_engine.gpu.loader import load_vulkan
    from ecs_engine.render.graph.access import RAY_TRACING_ONLY
    from ecs_engine.render.graph.barriers import dependency_info

    vk = load_vulkan()
    g = make(
        ("shadow", lambda b: (b.create("z", DEPTH), b.write("z", Access.DEPTH_WRITE, load=Load.CLEAR))),
        ("light", lambda b: (b.read("z", Access.DEPTH_SAMPLED), b.side_effect())),
    )
    rows = g.compiled.barriers.before["light"]
    aspects = {"z": vk.VK_IMAGE_ASPECT_DEPTH_BIT}
    ray = vk.VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR
    shaders = vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT
    kept = dependency_info(vk, rows, {"z": vk.ffi.NULL}, {}, aspects)
    assert kept.pImageMemoryBarriers[0].dstStageMask == shaders | ray
    dropped = dependency_info(vk, rows, {"z": vk.ffi.NULL}, {}, aspects, RAY_TRACING_ONLY)
    assert dropped.pImageMemoryBarriers[0].dstStageMask == shaders
