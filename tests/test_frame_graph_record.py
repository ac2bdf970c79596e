"""What the frame graph gives the frame around its passes: never-replayable keys, marks between
passes, store ops, the first barrier of an import chained with a semaphore's wait stage, cached
renderings and secondaries' inheritance (planned, then on lavapipe with validation on)."""

from __future__ import annotations

import numpy as np
import pytest
import test_frame_graph_gpu as gpu
from test_frame_graph import Step, clear, copy, make, readback
from test_frame_graph_gpu import Blit, Clear, Readback, pattern

from ecs_engine.errors import UsageError
from ecs_engine.render.graph import UNREPLAYABLE, Access, FrameGraph, ImageDesc, Load, Pass

DEPTH = "VK_FORMAT_D32_SFLOAT"
run = gpu.run  # the fixture: a graph of passes executed on the shared device, read back


def test_unreplayable_equals_no_key_and_makes_the_graph_unreplayable():
    assert UNREPLAYABLE != UNREPLAYABLE and UNREPLAYABLE is FrameGraph.UNREPLAYABLE
    g = FrameGraph(None)
    g.add_pass(Step("a", clear("x"), key=("a", 1)))
    g.add_pass(Step("ui", copy("x", "y"), key=UNREPLAYABLE))
    g.add_pass(Step("show", readback("x")))
    g.compile((8, 8))
    assert g.culled == ["ui"] and g.replayable()  # a culled pass's key does not count
    assert g.key() == g.key()
    g.add_pass(Step("show_y", readback("y")))
    g.compile((8, 8))
    assert not g.replayable()
    assert g.key() != g.key()  # the same graph, asked twice: never the same frame


def test_on_pass_end_is_called_after_each_pass_that_runs():
    marks = []
    graph = FrameGraph(gpu.shared_device())
    graph.add_pass(Clear("clear", "a"))
    graph.add_pass(gpu.NeverRecorded())
    graph.add_pass(Blit("flip", "a", "b"))
    graph.add_pass(Readback("b"))
    out = gpu.Buffer(graph.device, gpu.W * gpu.H * 8, graph.device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu.HOST)
    try:
        graph.import_buffer("out", handle=out.handle, size=out.size)
        graph.compile((gpu.W, gpu.H))
        graph.device.submit_once(lambda cb: graph.execute(cb, on_pass_end=marks.append))
        pixels = out.array(np.float16, (gpu.H, gpu.W, 4)).copy()
    finally:
        graph.destroy()
        out.destroy()
    assert marks == ["clear", "flip", "readback"]
    np.testing.assert_array_equal(pixels, np.flipud(pattern()))


def stores(g):
    return sorted((name, use.resource) for name, use in g.compiled.structure.dont_store)


def test_writes_nothing_later_reads_store_dont_care():
    msaa = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT", samples=4)

    def scene(b):
        b.create("ms", msaa)
        b.create("hdr", ImageDesc())
        b.create("depth", ImageDesc(format="VK_FORMAT_D32_SFLOAT", samples=4))
        b.write("ms", Access.COLOR_WRITE, load=Load.CLEAR)
        b.write("depth", Access.DEPTH_WRITE, load=Load.CLEAR)
        b.write("hdr", Access.RESOLVE_WRITE)

    g = make(("scene", scene), ("tone", lambda b: (b.read("hdr", Access.FRAGMENT_SAMPLED), b.side_effect())))
    assert stores(g) == [("scene", "depth"), ("scene", "ms")]  # the resolve target is read: stored
    assert "writes ms COLOR_WRITE clear store dont_care" in g.describe()
    g = make(("scene", scene), ("ao", lambda b: (b.read("depth", Access.DEPTH_SAMPLED), b.side_effect())))
    assert stores(g) == [("scene", "hdr"), ("scene", "ms")]  # the depth is sampled later: stored
    g = make(("a", clear("x")), ("b", lambda b: b.write("x", Access.COLOR_READ_WRITE)), outputs=["x"])
    assert g.order == ["a", "b"] and stores(g) == []  # loaded by b, then an output


def test_an_msaa_image_stored_dont_care_still_resolves(run):
    msaa = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT", samples=4)
    graph, pixels = run([Clear("draw", "ms", desc=msaa, resolve="resolved"), Readback("resolved")])
    np.testing.assert_array_equal(pixels, pattern())
    assert stores(graph) == [("draw", "ms")]


def test_renderings_are_made_once_per_compile_and_recorded_again(run):
    graph, first = run([Clear("clear", "a"), Blit("flip", "a", "b"), Readback("b")])
    (made,) = graph._renderings.values()
    device = graph.device
    device.submit_once(graph.execute)  # the second frame reuses the structs
    (again,) = graph._renderings.values()
    assert again is made
    np.testing.assert_array_equal(first, np.flipud(pattern()))
    graph.compile((gpu.W - 2, gpu.H))  # new transients: new views, new structs
    assert graph._renderings == {}
    device.submit_once(graph.execute)
    (remade,) = graph._renderings.values()
    assert remade is not made


def test_attachment_formats_come_from_the_declarations_without_a_compile():
    from ecs_engine.gpu.loader import load_vulkan

    vk = load_vulkan()
    g = FrameGraph(None)
    msaa = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT", samples=4)
    g.add_pass(Step("scene", lambda b: (b.create("ms", msaa), b.create("z", ImageDesc(format=DEPTH, samples=4)))))
    formats = g.attachment_formats(("ms",), "z")
    assert formats.colors == (vk.VK_FORMAT_R16G16B16A16_SFLOAT,) and formats.depth == vk.VK_FORMAT_D32_SFLOAT
    assert formats.samples == 4 and g.compiled is None
    g.add_pass(Step("ui", lambda b: b.create("one", ImageDesc())))
    with pytest.raises(UsageError, match="different sample counts"):
        g.attachment_formats(("ms", "one"))
    with pytest.raises(UsageError, match="'nope' is neither"):
        g.attachment_formats(("nope",))


class DrawnBySecondary(Pass):
    """Clears "a" by its load op; the rectangle is cleared by a secondary recorded before the
    primary was begun, with the graph's inheritance."""

    name = "secondary"

    def __init__(self):
        self.secondary = None

    def setup(self, b):
        b.create("a", gpu.HDR)
        b.write("a", Access.COLOR_WRITE, load=Load.CLEAR, clear=gpu.BACK)

    def record(self, cb, ctx):
        ctx.begin_rendering(colors=("a",), secondaries=True)
        ctx.vk.vkCmdExecuteCommands(cb, 1, [self.secondary])
        ctx.end_rendering()


def test_a_secondary_begun_before_the_primary_draws_inside_the_pass():
    from ecs_engine.gpu.secondary import SecondaryBuffers, end_command_buffer

    device = gpu.shared_device()
    vk = device.vk
    graph = FrameGraph(device)
    secondaries = SecondaryBuffers(device, 1)
    out = gpu.Buffer(device, gpu.W * gpu.H * 8, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu.HOST)
    try:
        draw = DrawnBySecondary()
        graph.add_pass(draw)
        graph.add_pass(Readback("a"))
        graph.import_buffer("out", handle=out.handle, size=out.size)
        begin = graph.inheritance(secondaries, ("a",))  # before compile and before any primary
        assert graph.inheritance(secondaries, ("a",)) is begin
        sec = draw.secondary = secondaries.begin(0, begin)
        x, y, w, h = gpu.RECT
        value = vk.VkClearValue(color=vk.VkClearColorValue(float32=list(gpu.SPOT)))
        attachment = vk.VkClearAttachment(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, colorAttachment=0, clearValue=value)
        rect = vk.VkClearRect(
            rect=vk.VkRect2D(vk.VkOffset2D(x, y), vk.VkExtent2D(w, h)), baseArrayLayer=0, layerCount=1
        )
        vk.vkCmdClearAttachments(sec, 1, [attachment], 1, [rect])
        end_command_buffer(vk, sec)
        graph.compile((gpu.W, gpu.H))
        device.submit_once(graph.execute)
        pixels = out.array(np.float16, (gpu.H, gpu.W, 4)).copy()
    finally:
        graph.destroy()
        secondaries.destroy()
        out.destroy()
    np.testing.assert_array_equal(pixels, pattern())
