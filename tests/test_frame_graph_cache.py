"""What keeps a frame graph's per-frame check cheap (render/graph/): passes' `declares()` standing
in for their setup, imports made once per distinct arguments or token, and the key asked once.
Device-free: the graph plans only."""

from __future__ import annotations

import pytest

from ecs_engine.render.graph import SETUP_EACH_COMPILE, UNREPLAYABLE, Access, FrameGraph, ImageDesc, Load, Pass

HDR = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT")


class Drawn(Pass):
    """Clears "hdr", or also "extra" when `self.extra`; counts its setups. `honest`: whether
    declares() names what setup reads (`extra`)."""

    name = "drawn"

    def __init__(self, honest: bool = True, mark=None) -> None:
        self.extra, self.honest, self.setups, self.mark = False, honest, 0, mark

    def setup(self, b) -> None:
        self.setups += 1
        b.create("hdr", HDR)
        b.write("hdr", Access.COLOR_WRITE, load=Load.CLEAR)
        if self.extra:
            b.create("extra", HDR)
            b.write("extra", Access.COLOR_WRITE, load=Load.CLEAR)
            b.side_effect()

    def declares(self):
        if self.mark is not None:
            return self.mark
        return self.extra if self.honest else ()


def graph_of(p: Pass) -> FrameGraph:
    g = FrameGraph(None)
    g.add_pass(p)
    g.output("hdr")
    return g


@pytest.fixture
def unverified(monkeypatch):
    """The graph as it runs outside the tests (conftest.py turns verify_declares on)."""
    monkeypatch.setattr(FrameGraph, "verify_declares", False)


def test_an_unchanged_declares_skips_setup_and_the_plan(unverified):
    p = Drawn()
    g = graph_of(p)
    g.compile((8, 8))
    setups, compiles = p.setups, g.compiles
    for _ in range(5):
        g.compile((8, 8))
    assert (p.setups, g.compiles) == (setups, compiles)  # nothing asked again
    p.extra = True  # declares() moves: setup again, and a new plan with the second image
    g.compile((8, 8))
    assert p.setups == setups + 1 and g.compiles == compiles + 1
    assert any(n == "extra" for n in g.compiled.structure.resources)


def test_setup_each_compile_is_the_default():
    class Plain(Drawn):
        def declares(self):
            return SETUP_EACH_COMPILE

    p = Plain()
    g = graph_of(p)
    g.compile((8, 8))
    g.compile((8, 8))
    assert p.setups == 2
    assert Pass().declares() is SETUP_EACH_COMPILE


def test_verify_declares_catches_a_pass_that_hides_a_change():
    """With verify on (the tests), a changed declaration under an equal declares() fails loudly."""
    assert FrameGraph.verify_declares  # tests/conftest.py
    p = Drawn(honest=False)
    g = graph_of(p)
    g.compile((8, 8))
    p.extra = True
    with pytest.raises(AssertionError, match=r"drawn.*declares"):
        g.compile((8, 8))


def test_without_verify_a_dishonest_declares_would_keep_a_stale_plan(unverified):
    """Why the tests verify: the same pass, unverified, keeps its old declarations."""
    p = Drawn(honest=False)
    g = graph_of(p)
    g.compile((8, 8))
    p.extra = True
    g.compile((8, 8))
    assert "extra" not in g.compiled.structure.resources


def test_imports_are_made_once_per_arguments_and_a_new_shape_recompiles():
    g = FrameGraph(None)

    class Reads(Pass):
        name = "reads"

        def setup(self, b):
            b.read("buf", Access.COMPUTE_READ)
            b.side_effect()

    g.add_pass(Reads())
    g.import_buffer("buf", handle=1, size=64)
    g.compile((8, 8))
    first, compiles = g._table.by_name["buf"], g.compiles
    g.import_buffer("buf", handle=2, size=64)  # another slot's buffer: same shape
    g.compile((8, 8))
    second = g._table.by_name["buf"]
    g.import_buffer("buf", handle=1, size=64)  # back to the first: the same import again
    assert g._table.by_name["buf"] is first and second is not first
    g.compile((8, 8))
    assert g.compiles == compiles  # handles alone never recompile
    assert g.key()[-1] == (("buf", 1, None),)
    g.import_buffer("buf", handle=1, size=128)  # a new size: a new plan
    g.compile((8, 8))
    assert g.compiles == compiles + 1


def test_a_token_stands_for_the_arguments():
    g = FrameGraph(None)
    assert not g.reuse_import("buf", ("slot0",))  # nothing made for it yet
    g.import_buffer("buf", handle=7, size=64, token=("slot0",))
    g.import_buffer("buf", handle=8, size=64, token=("slot1",))
    assert g.reuse_import("buf", ("slot0",))
    assert g._table.by_name["buf"].handle == 7
    assert g._table.handles() == (("buf", 7, None),)
    assert not g.reuse_import("buf", ("slot2",))


def test_key_with_replayable_is_none_when_a_running_pass_is_unreplayable():
    class Ui(Drawn):
        def key(self):
            return UNREPLAYABLE if self.extra else ("ui", 1)

    p = Ui()
    g = graph_of(p)
    g.compile((8, 8))
    assert g.key(replayable=True) == g.key() == (("drawn", ("ui", 1)), (8, 8), ())
    p.extra = True
    g.compile((8, 8))
    assert g.key(replayable=True) is None
    assert g.key() != g.key()  # the plain key never equals itself then
