"""The frame graph's planning, without a device: order, errors, culling, lifetimes, the aliasing
packing and the barrier plan (render/graph/)."""

from __future__ import annotations

import random

import pytest

from ecs_engine.errors import UsageError
from ecs_engine.render.graph import Access, BufferDesc, FrameGraph, ImageDesc, Load, Pass
from ecs_engine.render.graph.transient import Requirement, pack

HDR = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT")


class Step(Pass):
    """A pass whose setup is a function of its builder (tests declare inline)."""

    def __init__(self, name, setup, key=None):
        self.name = name
        self._setup = setup
        self._key = key

    def setup(self, b):
        self._setup(b)

    def key(self):
        return self._key


def make(*steps, outputs=(), extent=(64, 48)):
    g = FrameGraph(None)
    for name, setup in steps:
        g.add_pass(Step(name, setup))
    for o in outputs:
        g.output(o)
    g.compile(extent)
    return g


def clear(name, desc=HDR):
    return lambda b: (b.create(name, desc), b.write(name, Access.COLOR_WRITE, load=Load.CLEAR))


def copy(src, dst, desc=HDR):
    def setup(b):
        b.create(dst, desc)
        b.read(src, Access.TRANSFER_READ)
        b.write(dst, Access.TRANSFER_WRITE)

    return setup


def readback(src):
    def setup(b):
        b.read(src, Access.TRANSFER_READ)
        b.side_effect()

    return setup


def test_passes_run_in_the_order_added_and_before_inserts():
    g = FrameGraph(None)
    g.add_pass(Step("a", clear("x")))
    g.add_pass(Step("c", readback("y")))
    g.add_pass(Step("b", copy("x", "y")), before="c")
    g.compile((8, 8))
    assert g.order == ["a", "b", "c"] and g.culled == []
    with pytest.raises(UsageError, match="already has a pass named 'a'"):
        g.add_pass(Step("a", clear("z")))
    with pytest.raises(UsageError, match="no pass 'nope' to add 'd' before"):
        g.add_pass(Step("d", clear("z")), before="nope")


def test_a_read_of_what_nobody_wrote_before_is_an_error():
    with pytest.raises(UsageError, match=r"'b' reads 'x', which no pass before it writes .*\(written only by a, added"):
        make(("b", readback("x")), ("a", clear("x")))
    with pytest.raises(UsageError, match="reads 'ghost', which no pass creates and the graph does not import"):
        make(("b", readback("ghost")))
    g = FrameGraph(None)  # an imported image needs no writer
    g.import_image(
        "old",
        handle=1,
        view=2,
        format="R8G8B8A8_UNORM",
        extent=(8, 8),
        layout_before="SHADER_READ_ONLY_OPTIMAL",
        layout_after="SHADER_READ_ONLY_OPTIMAL",
    )
    g.add_pass(Step("b", readback("old")))
    g.compile((8, 8))
    assert g.order == ["b"]


def test_declarations_that_cannot_work_say_why():
    with pytest.raises(UsageError, match="COLOR_WRITE, which writes: use write"):
        make(("a", lambda b: (b.create("x", HDR), b.read("x", Access.COLOR_WRITE))))
    with pytest.raises(UsageError, match="buffer 'buf' as COLOR_WRITE, an image access"):
        make(("a", lambda b: (b.create("buf", BufferDesc(64)), b.write("buf", Access.COLOR_WRITE))))
    with pytest.raises(UsageError, match="mip 2 of 'x', which has 1 mip"):
        make(("a", lambda b: (b.create("x", HDR), b.write("x", Access.TRANSFER_WRITE, mip=2))))
    with pytest.raises(UsageError, match="as both TRANSFER_WRITE and COMPUTE_SAMPLED, which need different layouts"):
        make(
            ("a", clear("x")),
            ("b", lambda b: (b.write("x", Access.TRANSFER_WRITE), b.read("x", Access.COMPUTE_SAMPLED))),
        )
    with pytest.raises(UsageError, match="creates 'x', but pass 'a' creates it too"):
        make(("a", clear("x")), ("b", clear("x")))
    with pytest.raises(UsageError, match="mips >= 1"):
        ImageDesc(mips=0)


def test_passes_whose_writes_reach_no_output_are_culled_transitively():
    g = make(
        ("a", clear("x")),
        ("unused", copy("x", "y")),  # y feeds only z, which nobody reads
        ("unused2", copy("y", "z")),
        ("b", copy("x", "w")),
        ("show", readback("w")),
    )
    assert g.order == ["a", "b", "show"] and g.culled == ["unused", "unused2"]
    assert set(g.compiled.structure.lifetimes) == {"x", "w"}  # culled passes' transients are not made
    g = make(("a", clear("x")), ("b", copy("x", "y")), outputs=["y"])  # an output is a root
    assert g.order == ["a", "b"]
    g = make(("a", clear("x")), ("b", copy("x", "y")))  # nothing needs anything
    assert g.order == [] and g.culled == ["a", "b"]


def test_a_write_that_discards_does_not_need_the_writer_before_it():
    g = make(
        ("first", clear("x")),
        ("second", lambda b: b.write("x", Access.COLOR_WRITE, load=Load.CLEAR)),
        ("show", readback("x")),
    )
    assert g.culled == ["first"]
    g = make(
        ("first", clear("x")), ("second", lambda b: b.write("x", Access.COLOR_READ_WRITE)), ("show", readback("x"))
    )
    assert g.culled == []  # blending over it keeps it


CHAIN = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT", size=(16, 16), mips=3)


def mip_chain_graph():
    def base(b):
        b.create("chain", CHAIN)
        b.write("chain", Access.COLOR_WRITE, mip=0, load=Load.CLEAR)

    def down(src, dst):
        return lambda b: (
            b.read("chain", Access.TRANSFER_READ, mip=src),
            b.write("chain", Access.TRANSFER_WRITE, mip=dst),
        )

    def show(b):
        b.read("chain", Access.TRANSFER_READ, mip=1)
        b.side_effect()

    return make(("base", base), ("down1", down(0, 1)), ("down2", down(1, 2)), ("show", show))


def test_culling_follows_mips():
    g = mip_chain_graph()
    assert g.order == ["base", "down1", "show"] and g.culled == ["down2"]  # nobody reads mip 2


def test_barriers_between_mips_come_from_the_graph():
    plan = mip_chain_graph().compiled.barriers
    (base,) = plan.before["base"]
    assert (base.resource, base.base_mip, base.old_layout, base.new_layout) == (
        "chain",
        0,
        "UNDEFINED",
        "COLOR_ATTACHMENT_OPTIMAL",
    )
    src0, dst1 = plan.before["down1"]
    assert (src0.base_mip, src0.old_layout, src0.new_layout) == (0, "COLOR_ATTACHMENT_OPTIMAL", "TRANSFER_SRC_OPTIMAL")
    assert src0.src_stages == {"COLOR_ATTACHMENT_OUTPUT"} and src0.src_access == {"COLOR_ATTACHMENT_WRITE"}
    assert src0.dst_stages == {"TRANSFER"} and src0.dst_access == {"TRANSFER_READ"}
    assert (dst1.base_mip, dst1.old_layout, dst1.new_layout) == (1, "UNDEFINED", "TRANSFER_DST_OPTIMAL")
    (show,) = plan.before["show"]
    assert (show.base_mip, show.old_layout, show.new_layout) == (1, "TRANSFER_DST_OPTIMAL", "TRANSFER_SRC_OPTIMAL")
    assert show.src_access == {"TRANSFER_WRITE"} and show.dst_access == {"TRANSFER_READ"}


def test_reads_of_a_visible_write_need_no_second_barrier_and_writes_wait_for_reads():
    def both(b):
        b.create("y", HDR)
        b.read("x", Access.COMPUTE_SAMPLED)
        b.write("y", Access.COMPUTE_WRITE)
        b.side_effect()

    g = make(
        ("a", clear("x")),
        ("b", both),
        ("c", lambda b: (b.read("x", Access.COMPUTE_SAMPLED), b.side_effect())),
        ("d", lambda b: b.write("x", Access.COLOR_READ_WRITE)),
        ("e", readback("x")),
    )
    plan = g.compiled.barriers
    assert [r.resource for r in plan.before["b"]] == ["x", "y"]
    assert plan.before["c"] == []  # the same stage already saw the write
    (back,) = plan.before["d"]  # back to an attachment: after the reads (and the write before them)
    assert back.old_layout == "SHADER_READ_ONLY_OPTIMAL" and "COMPUTE_SHADER" in back.src_stages
    assert back.new_layout == "COLOR_ATTACHMENT_OPTIMAL" and back.dst_access == {
        "COLOR_ATTACHMENT_READ",
        "COLOR_ATTACHMENT_WRITE",
    }


def test_mips_with_the_same_barrier_become_one_row():
    def all_mips(b):
        b.create("chain", CHAIN)
        b.write("chain", Access.TRANSFER_WRITE)

    g = make(("a", all_mips), ("b", lambda b: (b.read("chain", Access.FRAGMENT_SAMPLED), b.side_effect())))
    (row,) = g.compiled.barriers.before["b"]
    assert (row.base_mip, row.mip_count, row.new_layout) == (0, 3, "SHADER_READ_ONLY_OPTIMAL")


def test_imports_start_in_layout_before_and_end_in_layout_after():
    g = FrameGraph(None)
    g.import_image(
        "swap",
        handle=1,
        view=2,
        format="B8G8R8A8_SRGB",
        extent=(64, 48),
        layout_before="UNDEFINED",
        layout_after="PRESENT_SRC_KHR",
    )
    g.import_image(
        "unused",
        handle=3,
        view=4,
        format="R8G8B8A8_UNORM",
        extent=(8, 8),
        layout_before="GENERAL",
        layout_after="SHADER_READ_ONLY_OPTIMAL",
    )
    g.add_pass(Step("draw", lambda b: (b.write("swap", Access.COLOR_WRITE, load=Load.CLEAR), b.side_effect())))
    g.compile((64, 48))
    (first,) = g.compiled.barriers.before["draw"]
    assert first.old_layout == "UNDEFINED" and first.src_stages == {"ALL_COMMANDS"}
    swap, unused = g.compiled.barriers.after
    assert (swap.old_layout, swap.new_layout, swap.dst_stages) == (
        "COLOR_ATTACHMENT_OPTIMAL",
        "PRESENT_SRC_KHR",
        {"NONE"},
    )
    assert (unused.old_layout, unused.new_layout) == ("GENERAL", "SHADER_READ_ONLY_OPTIMAL")


def aliasing_graph():
    return make(("p0", clear("t1")), ("p1", copy("t1", "t2")), ("p2", copy("t2", "t3")), ("p3", readback("t3")))


def test_transients_with_disjoint_lifetimes_share_memory():
    g = aliasing_graph()
    s, packing = g.compiled.structure, g.compiled.packing
    assert s.lifetimes == {"t1": (0, 1), "t2": (1, 2), "t3": (2, 3)}
    p = packing.placements
    assert (p["t1"].heap, p["t1"].offset) == (p["t3"].heap, p["t3"].offset) and p["t2"].offset != p["t1"].offset
    assert g.transient_bytes == 2 * p["t1"].size and g.unaliased_bytes == 3 * p["t1"].size
    # t3 starts from UNDEFINED after t1's last use (a transfer read) in the same bytes
    (t3,) = [r for r in g.compiled.barriers.before["p2"] if r.resource == "t3"]
    assert t3.old_layout == "UNDEFINED" and "TRANSFER" in t3.src_stages
    (t1,) = g.compiled.barriers.before["p0"]
    # nothing of this frame was in its bytes before; the frame before (in flight) drew into t1
    # and copied through t3 there: its first use waits for both
    assert t1.src_stages == {"COLOR_ATTACHMENT_OUTPUT", "TRANSFER"}


def test_a_transients_first_use_waits_for_the_frame_before():
    """Frames in flight run one graph over the same transients: a transient's first use must
    wait for the previous submission's uses of its memory (a barrier's first scope reaches
    earlier submissions), or the next frame writes what the last one still reads."""
    g = aliasing_graph()
    (t2,) = [r for r in g.compiled.barriers.before["p1"] if r.resource == "t2"]
    assert t2.old_layout == "UNDEFINED" and t2.src_stages == {"TRANSFER"}


def test_packing_never_overlaps_images_alive_together():
    rng = random.Random(36)
    for _ in range(200):
        reqs = []
        for i in range(rng.randint(1, 9)):
            first = rng.randint(0, 6)
            align = rng.choice([1, 256, 4096])
            reqs.append(
                Requirement(
                    f"r{i}", rng.randint(1, 20_000), align, rng.choice([1, 3]), first, first + rng.randint(0, 3)
                )
            )
        packing = pack(reqs)
        for r in reqs:
            place = packing.placements[r.name]
            assert place.offset % r.alignment == 0
            assert place.offset + r.size <= packing.heap_sizes[place.heap]
            for o in reqs:
                if o is not r and o.first <= r.last and r.first <= o.last and o.type_bits == r.type_bits:
                    assert not packing.overlapping(r.name, o.name), (r, o)
        assert packing.transient_bytes <= packing.unaliased_bytes + sum(r.alignment for r in reqs)


def test_compile_is_cached_until_something_changes():
    g = FrameGraph(None)
    size = {"scale": 1.0}
    g.add_pass(Step("a", lambda b: (b.create("x", ImageDesc(scale=size["scale"])), b.write("x", Access.COLOR_WRITE))))
    g.add_pass(Step("show", readback("x")))
    g.compile((64, 48))
    first = g.compiled
    g.compile((64, 48))
    assert g.compiles == 1 and g.compiled is first
    g.compile((32, 48))
    assert g.compiles == 2
    size["scale"] = 0.5  # a pass's declaration changed
    g.compile((32, 48))
    assert g.compiles == 3 and g.compiled.structure.resources["x"].desc.scale == 0.5
    g.output("x")
    g.compile((32, 48))
    assert g.compiles == 4


def test_key_is_the_passes_keys_the_extent_and_the_imported_handles():
    g = FrameGraph(None)
    g.import_image(
        "swap",
        handle=11,
        view=12,
        format="B8G8R8A8_SRGB",
        extent=(8, 8),
        layout_before="UNDEFINED",
        layout_after="PRESENT_SRC_KHR",
    )
    g.add_pass(Step("draw", lambda b: (b.write("swap", Access.COLOR_WRITE), b.side_effect()), key=("cubes", 3)))
    g.add_pass(Step("culled", clear("x"), key="never"))
    g.compile((8, 8))
    assert g.key() == (("draw", ("cubes", 3)), (8, 8), (("swap", 11, 12),))
    g.import_image(
        "swap",
        handle=21,
        view=22,
        format="B8G8R8A8_SRGB",
        extent=(8, 8),
        layout_before="UNDEFINED",
        layout_after="PRESENT_SRC_KHR",
    )
    g.compile((8, 8))
    assert g.compiles == 1 and g.key()[-1] == (("swap", 21, 22),)  # a new handle recompiles nothing


def test_describe_lists_passes_accesses_barriers_and_memory():
    text = aliasing_graph().describe()
    assert text.startswith("frame graph 64x48: 4 passes")
    assert "  1 p1\n      reads  t1 TRANSFER_READ\n      writes t2 TRANSFER_WRITE dont_care" in text
    assert "barrier t3[mip 0] UNDEFINED -> TRANSFER_DST_OPTIMAL (COLOR_ATTACHMENT_OUTPUT|TRANSFER -> TRANSFER)" in text
    assert "t1: R16G16B16A16_SFLOAT 64x48, 24,576 bytes at heap 0 + 0, passes 0..1" in text
    assert "  3 p3 (side effect)" in text


def test_every_name_in_the_access_table_is_a_vulkan_name():
    from ecs_engine.gpu.loader import load_vulkan
    from ecs_engine.render.graph.resources import flags

    vk = load_vulkan()
    for access in Access:
        u = access.usage
        assert flags(vk, "VK_PIPELINE_STAGE_2_", u.stages) or u.stages == ("NONE",)
        assert flags(vk, "VK_ACCESS_2_", u.access) or u.access == ("NONE",)
        assert u.layout is None or hasattr(vk, f"VK_IMAGE_LAYOUT_{u.layout}")
        flags(vk, "VK_IMAGE_USAGE_", u.image_usage)
        flags(vk, "VK_BUFFER_USAGE_", u.buffer_usage)
