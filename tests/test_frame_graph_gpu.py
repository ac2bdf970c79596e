"""The frame graph on a device with validation on (conftest fails a test on any message): passes
that clear with dynamic rendering, copy and blit, read back into an imported host buffer and are
compared with NumPy; aliasing, per-mip barriers, culling, MSAA resolve, caching, and destroy."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import shared_device
from host_reads import host_barrier

from ecs_engine.gpu.memory import HOST, Buffer
from ecs_engine.render.graph import Access, BufferDesc, FrameGraph, ImageDesc, Load, Pass

W, H = 16, 12
BACK = (0.25, 0.5, 1.0, 1.0)
SPOT = (2.0, 0.0, 0.125, 0.5)
RECT = (2, 4, 6, 4)  # x, y, w, h: even, so 2x2 blocks stay whole when halved
HDR = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT")


def pattern(w=W, h=H, rect=RECT):
    img = np.empty((h, w, 4), np.float16)
    img[:] = BACK
    x, y, rw, rh = rect
    img[y : y + rh, x : x + rw] = SPOT
    return img


class Clear(Pass):
    """Clears `target` (at `mip`) by its load op, then a rectangle with vkCmdClearAttachments."""

    def __init__(self, name, target, desc=HDR, mip=0, resolve=None, resolve_desc=HDR):
        self.name, self.target, self.desc, self.mip = name, target, desc, mip
        self.resolve, self.resolve_desc = resolve, resolve_desc

    def setup(self, b):
        b.create(self.target, self.desc)
        b.write(self.target, Access.COLOR_WRITE, mip=self.mip, load=Load.CLEAR, clear=BACK)
        if self.resolve:
            b.create(self.resolve, self.resolve_desc)
            b.write(self.resolve, Access.RESOLVE_WRITE)

    def record(self, cb, ctx):
        vk = ctx.vk
        ctx.begin_rendering(colors=(self.target,), resolve=(self.resolve,) if self.resolve else None, mip=self.mip)
        x, y, w, h = RECT
        value = vk.VkClearValue(color=vk.VkClearColorValue(float32=list(SPOT)))
        attachment = vk.VkClearAttachment(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, colorAttachment=0, clearValue=value)
        rect = vk.VkClearRect(
            rect=vk.VkRect2D(vk.VkOffset2D(x, y), vk.VkExtent2D(w, h)), baseArrayLayer=0, layerCount=1
        )
        vk.vkCmdClearAttachments(cb, 1, [attachment], 1, [rect])
        ctx.end_rendering()


def layers(vk, mip=0, aspect=None):
    aspect = aspect or vk.VK_IMAGE_ASPECT_COLOR_BIT
    return vk.VkImageSubresourceLayers(aspectMask=aspect, mipLevel=mip, baseArrayLayer=0, layerCount=1)


class Blit(Pass):
    """Blits src (mip) into dst (mip), mirrored vertically or horizontally, or halved."""

    def __init__(self, name, src, dst, flip="y", src_mip=None, dst_mip=None, desc=HDR):
        self.name, self.src, self.dst, self.flip, self.desc = name, src, dst, flip, desc
        self.src_mip, self.dst_mip = src_mip, dst_mip

    def setup(self, b):
        if self.src != self.dst:
            b.create(self.dst, self.desc)
        b.read(self.src, Access.TRANSFER_READ, mip=self.src_mip)
        b.write(self.dst, Access.TRANSFER_WRITE, mip=self.dst_mip)

    def record(self, cb, ctx):
        vk = ctx.vk
        src, dst = ctx.image(self.src), ctx.image(self.dst)
        sm, dm = self.src_mip or 0, self.dst_mip or 0
        (sw, sh), (dw, dh) = src.mip_extent(sm), dst.mip_extent(dm)
        ends = {"y": [(0, dh, 0), (dw, 0, 1)], "x": [(dw, 0, 0), (0, dh, 1)], "": [(0, 0, 0), (dw, dh, 1)]}[self.flip]
        region = vk.VkImageBlit(
            srcSubresource=layers(vk, sm),
            srcOffsets=[vk.VkOffset3D(0, 0, 0), vk.VkOffset3D(sw, sh, 1)],
            dstSubresource=layers(vk, dm),
            dstOffsets=[vk.VkOffset3D(*e) for e in ends],
        )
        vk.vkCmdBlitImage(
            cb,
            src.handle,
            vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
            dst.handle,
            vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
            1,
            [region],
            vk.VK_FILTER_NEAREST,
        )


class Readback(Pass):
    """Copies `src` (mip) into the imported buffer "out", made visible to the host."""

    def __init__(self, src, mip=None, name="readback", depth=False):
        self.name, self.src, self.mip, self.depth = name, src, mip, depth

    def setup(self, b):
        b.read(self.src, Access.TRANSFER_READ, mip=self.mip)
        b.write("out", Access.TRANSFER_WRITE)
        b.side_effect()

    def record(self, cb, ctx):
        vk = ctx.vk
        image, out = ctx.image(self.src), ctx.buffer("out")
        w, h = image.mip_extent(self.mip or 0)
        region = vk.VkBufferImageCopy(
            bufferOffset=0,
            bufferRowLength=0,
            bufferImageHeight=0,
            imageSubresource=layers(vk, self.mip or 0, vk.VK_IMAGE_ASPECT_DEPTH_BIT if self.depth else None),
            imageOffset=vk.VkOffset3D(0, 0, 0),
            imageExtent=vk.VkExtent3D(w, h, 1),
        )
        vk.vkCmdCopyImageToBuffer(cb, image.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, out.handle, 1, [region])
        host_barrier(vk, cb)


class NeverRecorded(Pass):
    name = "debug_view"
    recorded = 0

    def setup(self, b):
        b.create("debug", HDR)
        b.write("debug", Access.COLOR_WRITE, load=Load.CLEAR)

    def record(self, cb, ctx):
        NeverRecorded.recorded += 1


@pytest.fixture
def run():
    """Builds a graph of the given passes on the shared device with the buffer "out" imported,
    compiles, executes once and returns (graph, pixels of `shape`); destroys it all after."""
    device = shared_device()
    made = []

    def go(passes, shape=(H, W, 4), extent=(W, H)):
        out = Buffer(device, int(np.prod(shape)) * 2, device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
        graph = FrameGraph(device)
        made.extend([out, graph])
        graph.import_buffer("out", handle=out.handle, size=out.size)
        for p in passes:
            graph.add_pass(p)
        graph.compile(extent)
        device.submit_once(graph.execute)
        return graph, out.array(np.float16, shape).copy()

    yield go
    for thing in reversed(made):
        thing.destroy()


def test_three_passes_clear_blit_and_read_back(run):
    NeverRecorded.recorded = 0
    graph, pixels = run([Clear("clear", "a"), NeverRecorded(), Blit("flip", "a", "b"), Readback("b")])
    np.testing.assert_array_equal(pixels, np.flipud(pattern()))
    assert graph.order == ["clear", "flip", "readback"] and graph.culled == ["debug_view"]
    assert NeverRecorded.recorded == 0 and "debug" not in graph.compiled.transients.images
    print(graph.describe())


def test_transients_with_disjoint_lifetimes_share_memory_and_stay_right(run):
    graph, pixels = run([Clear("p0", "t1"), Blit("p1", "t1", "t2", "y"), Blit("p2", "t2", "t3", "x"), Readback("t3")])
    np.testing.assert_array_equal(pixels, np.flipud(np.fliplr(pattern())))
    t = graph.compiled.transients
    assert t.memory["t1"] == t.memory["t3"] and t.absolute_offset["t1"] == t.absolute_offset["t3"]
    assert t.absolute_offset["t2"] != t.absolute_offset["t1"]
    assert graph.transient_bytes < graph.unaliased_bytes
    print(f"transient {graph.transient_bytes} bytes, unaliased {graph.unaliased_bytes}")


def test_a_mip_written_then_blitted_down_is_read_after_the_graphs_barrier(run):
    chain = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT", size=(W, H), mips=2)

    class Base(Clear):
        def setup(self, b):
            b.create("chain", chain)
            b.write("chain", Access.COLOR_WRITE, mip=0, load=Load.CLEAR, clear=BACK)

    passes = [Base("base", "chain", mip=0), Blit("down", "chain", "chain", "", 0, 1), Readback("chain", mip=1)]
    graph, pixels = run(passes, shape=(H // 2, W // 2, 4))
    np.testing.assert_array_equal(pixels, pattern()[::2, ::2])
    rows = {(r.resource, r.base_mip): r for r in graph.compiled.barriers.before["down"]}
    assert rows[("chain", 0)].old_layout == "COLOR_ATTACHMENT_OPTIMAL"
    assert rows[("chain", 0)].new_layout == "TRANSFER_SRC_OPTIMAL"
    assert rows[("chain", 1)].new_layout == "TRANSFER_DST_OPTIMAL"


def test_msaa_renders_resolved_into_a_single_sample_image(run):
    msaa = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT", samples=4)
    graph, pixels = run([Clear("draw", "ms", desc=msaa, resolve="resolved"), Readback("resolved")])
    np.testing.assert_array_equal(pixels, pattern())
    assert graph.compiled.transients.images["ms"].samples == 4


class Depth(Pass):
    """Clears depth by its load op, then a rectangle deeper (vkCmdClearAttachments)."""

    name = "depth"

    def setup(self, b):
        b.create("z", ImageDesc(format="VK_FORMAT_D32_SFLOAT"))
        b.write("z", Access.DEPTH_WRITE, load=Load.CLEAR, clear=(0.25, 0.0, 0.0, 0.0))

    def record(self, cb, ctx):
        vk = ctx.vk
        ctx.begin_rendering(depth="z")
        x, y, w, h = RECT
        value = vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=0.75, stencil=0))
        attachment = vk.VkClearAttachment(aspectMask=vk.VK_IMAGE_ASPECT_DEPTH_BIT, colorAttachment=0, clearValue=value)
        rect = vk.VkClearRect(
            rect=vk.VkRect2D(vk.VkOffset2D(x, y), vk.VkExtent2D(w, h)), baseArrayLayer=0, layerCount=1
        )
        vk.vkCmdClearAttachments(cb, 1, [attachment], 1, [rect])
        ctx.end_rendering()


class DepthTested(Pass):
    """Renders colour against the depth read-only (nothing drawn: the attachments are what counts)."""

    name = "tested"

    def setup(self, b):
        b.create("lit", HDR)
        b.write("lit", Access.COLOR_WRITE, load=Load.CLEAR, clear=BACK)
        b.read("z", Access.DEPTH_READ)
        b.side_effect()

    def record(self, cb, ctx):
        ctx.begin_rendering(colors=("lit",), depth="z")
        ctx.end_rendering()


def test_depth_written_then_tested_read_only_then_copied(run):
    graph, raw = run([Depth(), DepthTested(), Readback("z", depth=True)], shape=(H, W, 2))
    depth = raw.view(np.float32)[..., 0]
    expected = np.full((H, W), 0.25, np.float32)
    x, y, w, h = RECT
    expected[y : y + h, x : x + w] = 0.75
    np.testing.assert_array_equal(depth, expected)
    (to_read,) = graph.compiled.barriers.before["tested"][1:]
    assert (to_read.old_layout, to_read.new_layout) == (
        "DEPTH_STENCIL_ATTACHMENT_OPTIMAL",
        "DEPTH_STENCIL_READ_ONLY_OPTIMAL",
    )


class ToBuffers(Pass):
    """Copies image `src` into the transient buffer "staging", then (a second pass) that into "out"."""

    def __init__(self, name, src=None):
        self.name, self.src = name, src

    def setup(self, b):
        if self.src:
            b.create("staging", BufferDesc(W * H * 8))
            b.read(self.src, Access.TRANSFER_READ)
            b.write("staging", Access.TRANSFER_WRITE)
        else:
            b.read("staging", Access.TRANSFER_READ)
            b.write("out", Access.TRANSFER_WRITE)
            b.side_effect()

    def record(self, cb, ctx):
        vk = ctx.vk
        if self.src:
            region = vk.VkBufferImageCopy(imageSubresource=layers(vk), imageExtent=vk.VkExtent3D(W, H, 1))
            image = ctx.image(self.src).handle
            staging = ctx.buffer("staging").handle
            vk.vkCmdCopyImageToBuffer(cb, image, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging, 1, [region])
            return
        copy = vk.VkBufferCopy(srcOffset=0, dstOffset=0, size=W * H * 8)
        vk.vkCmdCopyBuffer(cb, ctx.buffer("staging").handle, ctx.buffer("out").handle, 1, [copy])
        host_barrier(vk, cb)


def test_a_transient_buffer_between_two_copies(run):
    graph, pixels = run([Clear("clear", "a"), ToBuffers("to_staging", "a"), ToBuffers("to_out")])
    np.testing.assert_array_equal(pixels, pattern())
    (row,) = [r for r in graph.compiled.barriers.before["to_out"] if r.resource == "staging"]
    assert row.src_access == {"TRANSFER_WRITE"} and row.dst_access == {"TRANSFER_READ"}


def test_a_second_compile_with_the_same_inputs_makes_nothing(run):
    device = shared_device()
    graph, first = run([Clear("clear", "a"), Blit("flip", "a", "b"), Readback("b")])
    made, version, calls = graph._owned.made, device.objects_version, device.allocator.allocate_calls
    graph.compile((W, H))
    assert (graph._owned.made, device.objects_version, device.allocator.allocate_calls) == (made, version, calls)
    assert graph.compiles == 1
    device.submit_once(graph.execute)  # a second frame from the same compile (images start where they ended)
    np.testing.assert_array_equal(first, np.flipud(pattern()))
    graph.compile((W // 2, H // 2))  # a new extent makes new transients
    assert graph.compiles == 2 and graph._owned.made > made


class Fill(Pass):
    name = "fill"

    def setup(self, b):
        b.write("slot", Access.TRANSFER_WRITE)

    def record(self, cb, ctx):
        slot = ctx.buffer("slot")
        ctx.vk.vkCmdFillBuffer(cb, slot.handle, 0, slot.size, 0x3C003C00)  # float16 ones


class CopyOut(Pass):
    name = "copy_out"

    def setup(self, b):
        b.read("slot", Access.TRANSFER_READ)
        b.write("out", Access.TRANSFER_WRITE)
        b.side_effect()

    def record(self, cb, ctx):
        slot, out = ctx.buffer("slot"), ctx.buffer("out")
        ctx.vk.vkCmdCopyBuffer(cb, slot.handle, out.handle, 1, [ctx.vk.VkBufferCopy(0, 0, slot.size)])
        host_barrier(ctx.vk, cb)


def test_the_barriers_of_alternating_frame_slot_buffers_are_made_once_per_slot():
    """A frame slot's buffers come round every other frame: each batch's VkDependencyInfo is
    kept per set of imports, not made again each frame (the indirect path's cull passes)."""
    device = shared_device()
    usage = device.vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT | device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
    slots = [Buffer(device, W * H * 8, usage, HOST) for _ in range(2)]
    out = Buffer(device, W * H * 8, device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
    graph = FrameGraph(device)
    try:
        graph.import_buffer("out", handle=out.handle, size=out.size)
        graph.add_pass(Fill())
        graph.add_pass(CopyOut())
        kept = None
        for frame in range(6):
            graph.import_slot_buffers({"slot": slots[frame % 2]})
            graph.compile((W, H))
            device.submit_once(graph.execute)
            if frame == 1:
                kept = {state: dict(rec.infos) for state, rec in graph._recordings.items()}
        assert graph.compiles == 1
        assert {state: dict(rec.infos) for state, rec in graph._recordings.items()} == kept
        assert [sorted(infos) for infos in kept.values()] == [["copy_out"], ["copy_out"]]  # one per slot
        ones = np.ones((H, W, 4), np.float16)
        np.testing.assert_array_equal(out.array(np.float16, (H, W, 4)), ones)
    finally:
        graph.destroy()
        for b in [*slots, out]:
            b.destroy()


def test_destroy_leaves_nothing_for_validation_to_report():
    """On a device of its own: a graph's objects all go with destroy() (validation reports any
    object still alive when the device is destroyed), and a leak is indeed reported."""
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance

    def session(destroy_graph):
        instance = Instance(validate=True)
        device = Device(instance)
        out = Buffer(device, W * H * 8, device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
        graph = FrameGraph(device)
        graph.import_buffer("out", handle=out.handle, size=out.size)
        for p in [Clear("p0", "t1"), Blit("p1", "t1", "t2"), Blit("p2", "t2", "t3", "x"), Readback("t3")]:
            graph.add_pass(p)
        graph.compile((W, H))
        device.submit_once(graph.execute)
        pixels = out.array(np.float16, (H, W, 4)).copy()
        if destroy_graph:
            graph.destroy()
            graph.destroy()  # idempotent
        out.destroy()
        device.destroy()
        instance.destroy()
        return instance.messages, pixels

    messages, pixels = session(destroy_graph=True)
    assert messages == []
    np.testing.assert_array_equal(pixels, np.flipud(np.fliplr(pattern())))
    leaked, _ = session(destroy_graph=False)
    assert any("VkImage" in m for m in leaked), leaked
