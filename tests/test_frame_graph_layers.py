"""Array layers (state per layer, barriers over layer ranges, rendering to one layer), partial
writes into a render area that keep the rest of the image, and an import's first barrier
chained with a semaphore's wait stage: planned without a device, then on lavapipe."""

from __future__ import annotations

import numpy as np
import pytest
import test_frame_graph_gpu as gpu
from test_frame_graph import Step, make
from test_frame_graph_gpu import BACK, RECT, SPOT, H, W, pattern

from ecs_engine.errors import UsageError
from ecs_engine.gpu.memory import Image
from ecs_engine.render.graph import Access, FrameGraph, ImageDesc, Load, Pass

run = gpu.run  # the fixture: a graph of passes executed on the shared device, read back
DEPTH = "VK_FORMAT_D32_SFLOAT"


def shadow_graph():
    g = FrameGraph(None)
    g.import_image(
        "shadows",
        handle=1,
        view=2,
        format=DEPTH,
        extent=(32, 32),
        layers=4,
        layer_views=(10, 11, 12, 13),
        layout_before="DEPTH_STENCIL_READ_ONLY_OPTIMAL",
        layout_after="DEPTH_STENCIL_READ_ONLY_OPTIMAL",
    )
    for k in (1, 3):
        g.add_pass(Step(f"shadow:{k}", lambda b, k=k: b.write("shadows", Access.DEPTH_WRITE, layer=k, load=Load.CLEAR)))
    g.add_pass(Step("light", lambda b: (b.read("shadows", Access.DEPTH_SAMPLED), b.side_effect())))
    g.output("shadows")
    g.compile((32, 32))
    return g


def test_layers_have_their_own_state_and_barriers_cover_layer_ranges():
    plan = shadow_graph().compiled.barriers
    (one,) = plan.before["shadow:1"]
    assert (one.base_layer, one.layer_count, one.old_layout) == (1, 1, "UNDEFINED")
    assert one.new_layout == "DEPTH_STENCIL_ATTACHMENT_OPTIMAL"
    rows = plan.before["light"]  # layers 1 and 3 were drawn; 0 and 2, still as imported, are
    # read in the layout they came in: no barrier (test_frame_graph_trims.py)
    drawn = [(r.base_layer, r.layer_count) for r in rows if r.old_layout == "DEPTH_STENCIL_ATTACHMENT_OPTIMAL"]
    assert drawn == [(1, 1), (3, 1)] and len(rows) == 2
    assert all(r.new_layout == "DEPTH_STENCIL_READ_ONLY_OPTIMAL" for r in rows)
    text = shadow_graph().describe()
    assert "barrier shadows[mip 0][layer 3] DEPTH_STENCIL_ATTACHMENT_OPTIMAL" in text  # a layer named even alone
    assert "barrier shadows[mip 0][layer 0]" not in text
    assert "imported shadows: D32_SFLOAT 32x32, 4 layers, DEPTH_STENCIL_READ_ONLY_OPTIMAL -> " in text


def test_a_use_of_every_layer_is_one_barrier_and_layers_are_checked():
    arr = ImageDesc(format="VK_FORMAT_R8G8B8A8_UNORM", layers=3)
    g = make(
        ("all", lambda b: (b.create("a", arr), b.write("a", Access.TRANSFER_WRITE))),
        ("read", lambda b: (b.read("a", Access.FRAGMENT_SAMPLED), b.side_effect())),
    )
    (row,) = g.compiled.barriers.before["read"]
    assert (row.base_layer, row.layer_count, row.mip_count) == (0, 3, 1)
    with pytest.raises(UsageError, match="layer 3 of 'a', which has 3 layer"):
        make(("x", lambda b: (b.create("a", arr), b.write("a", Access.TRANSFER_WRITE, layer=3), b.side_effect())))
    with pytest.raises(UsageError, match="reads layer 1 of 'a', which no pass before it writes"):
        make(
            ("x", lambda b: (b.create("a", arr), b.write("a", Access.TRANSFER_WRITE, layer=0))),
            ("y", lambda b: (b.read("a", Access.TRANSFER_READ, layer=1), b.side_effect())),
        )


def test_a_region_write_keeps_the_rest_so_it_follows_the_writer_before():
    def second(region):
        return lambda b: b.write("x", Access.COLOR_WRITE, load=Load.CLEAR, region=region)

    whole = lambda b: (b.create("x", ImageDesc()), b.write("x", Access.COLOR_WRITE, load=Load.CLEAR))
    show = lambda b: (b.read("x", Access.TRANSFER_READ), b.side_effect())
    g = make(("first", whole), ("second", second(True)), ("show", show))
    assert g.culled == []
    (row,) = g.compiled.barriers.before["second"]  # no UNDEFINED: the first pass's pixels stay
    assert row.old_layout == row.new_layout == "COLOR_ATTACHMENT_OPTIMAL"
    assert row.src_access == {"COLOR_ATTACHMENT_WRITE"}
    assert "writes x region COLOR_WRITE clear" in g.describe()
    g = make(("first", whole), ("second", second(False)), ("show", show))
    assert g.culled == ["first"] and g.compiled.barriers.before["second"][0].old_layout == "UNDEFINED"
    # a region write may be the first: there is nothing to keep yet
    g = make(("only", lambda b: (b.create("x", ImageDesc()), second(True)(b))), ("show", show))
    assert g.order == ["only", "show"]


def swap(g, stage="ALL_COMMANDS", handle=1):
    g.import_image(
        "swap",
        handle=handle,
        view=handle + 1,
        format="B8G8R8A8_SRGB",
        extent=(8, 8),
        layout_before="UNDEFINED",
        layout_after="PRESENT_SRC_KHR",
        stage_before=stage,
    )


def test_an_imports_first_barrier_waits_on_its_stage_before():
    g = FrameGraph(None)
    swap(g, "VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT")
    g.add_pass(Step("draw", lambda b: (b.write("swap", Access.COLOR_WRITE, load=Load.CLEAR), b.side_effect())))
    g.compile((8, 8))
    (first,) = g.compiled.barriers.before["draw"]
    assert first.src_stages == {"COLOR_ATTACHMENT_OUTPUT"} and first.dst_stages == {"COLOR_ATTACHMENT_OUTPUT"}
    assert (
        "imported swap: B8G8R8A8_SRGB 8x8, UNDEFINED after COLOR_ATTACHMENT_OUTPUT -> PRESENT_SRC_KHR" in g.describe()
    )
    swap(g, "COLOR_ATTACHMENT_OUTPUT", handle=5)  # the next image: nothing to compile
    g.compile((8, 8))
    assert g.compiles == 1
    swap(g)  # another stage: another plan
    g.compile((8, 8))
    assert g.compiles == 2 and g.compiled.barriers.before["draw"][0].src_stages == {"ALL_COMMANDS"}


class ClearLayer(Pass):
    """Clears one layer of the array "arr" (made by the pass of layer 0) to `value`, or a render
    area of it (keeping the rest) when `area` is given."""

    def __init__(self, layer, value, area=None, desc=None):
        self.name, self.layer, self.value, self.area, self.desc = f"layer:{layer}", layer, value, area, desc

    def setup(self, b):
        if self.desc is not None:
            b.create("arr", self.desc)
        b.write("arr", Access.COLOR_WRITE, layer=self.layer, load=Load.CLEAR, clear=self.value, region=bool(self.area))

    def record(self, cb, ctx):
        ctx.begin_rendering(colors=("arr",), layer=self.layer, area=self.area)
        ctx.end_rendering()


class ReadLayers(Pass):
    """Copies every layer of `src` into "out", layer after layer."""

    name = "readback"

    def __init__(self, src="arr", count=3):
        self.src, self.count = src, count

    def setup(self, b):
        b.read(self.src, Access.TRANSFER_READ)
        b.write("out", Access.TRANSFER_WRITE)
        b.side_effect()

    def record(self, cb, ctx):
        vk = ctx.vk
        sub = vk.VkImageSubresourceLayers(
            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0, baseArrayLayer=0, layerCount=self.count
        )
        region = vk.VkBufferImageCopy(imageSubresource=sub, imageExtent=vk.VkExtent3D(W, H, 1))
        image, out = ctx.image(self.src).handle, ctx.buffer("out").handle
        vk.vkCmdCopyImageToBuffer(cb, image, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, out, 1, [region])
        gpu.host_barrier(vk, cb)


def test_each_layer_rendered_alone_and_one_area_kept_around(run):
    desc = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT", layers=3)
    x, y, w, h = RECT
    passes = [
        ClearLayer(0, BACK, desc=desc),
        ClearLayer(1, (0.0, 1.0, 0.0, 1.0)),
        ClearLayer(2, BACK),
        ClearLayer(2, SPOT, area=(x, y, w, h)),
        ReadLayers(),
    ]
    passes[3].name = "area"
    graph, pixels = run(passes, shape=(3, H, W, 4))
    np.testing.assert_array_equal(pixels[0], np.broadcast_to(np.float16(BACK), (H, W, 4)))
    np.testing.assert_array_equal(pixels[1], np.broadcast_to(np.float16((0, 1, 0, 1)), (H, W, 4)))
    np.testing.assert_array_equal(pixels[2], pattern())  # the area cleared, the rest kept
    assert graph.compiled.transients.images["arr"].layers == 3
    (made,) = [m for k, m in graph._renderings.items() if k[0] == "area"]
    viewport, scissor = made.viewport[0], made.scissor[0]  # the render area's
    assert (viewport.x, viewport.y, viewport.width, viewport.height) == (x, y, w, h)
    assert (scissor.offset.x, scissor.offset.y, scissor.extent.width, scissor.extent.height) == (x, y, w, h)
    (to_read,) = graph.compiled.barriers.before["readback"][:1]
    assert (to_read.base_layer, to_read.layer_count) == (0, 3)


def test_an_imported_array_drawn_per_layer_after_the_acquire_stage(run):
    device = gpu.shared_device()
    vk = device.vk
    usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
    fmt = vk.VK_FORMAT_R16G16B16A16_SFLOAT
    image = Image(device, W, H, fmt, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT, layers=2)
    views = [image.layer_view(k) for k in range(2)]
    try:

        class Imported(ClearLayer):
            def setup(self, b):
                b.write("arr", Access.COLOR_WRITE, layer=self.layer, load=Load.CLEAR, clear=self.value)

        passes = [Imported(0, SPOT), Imported(1, BACK), ReadLayers(count=2)]
        graph = FrameGraph(device)
        graph.import_image(
            "arr",
            handle=image.handle,
            view=image.view,
            format=fmt,
            extent=(W, H),
            layers=2,
            layer_views=views,
            layout_before=vk.VK_IMAGE_LAYOUT_UNDEFINED,
            layout_after=vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
            stage_before="COLOR_ATTACHMENT_OUTPUT",
        )
        out = gpu.Buffer(device, 2 * W * H * 8, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu.HOST)
        graph.import_buffer("out", handle=out.handle, size=out.size)
        for p in passes:
            graph.add_pass(p)
        graph.compile((W, H))
        device.submit_once(graph.execute)
        pixels = out.array(np.float16, (2, H, W, 4)).copy()
        (first,) = graph.compiled.barriers.before["layer:0"]
        graph.destroy()
        out.destroy()
    finally:
        for view in views:
            vk.vkDestroyImageView(device.handle, view, None)
        image.destroy()
    assert first.src_stages == {"COLOR_ATTACHMENT_OUTPUT"}
    np.testing.assert_array_equal(pixels[0], np.broadcast_to(np.float16(SPOT), (H, W, 4)))
    np.testing.assert_array_equal(pixels[1], np.broadcast_to(np.float16(BACK), (H, W, 4)))
