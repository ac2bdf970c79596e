"""The child process that builds levels of detail for windows (render/assets/lod_worker.py): the same
levels as an inline build, read-only, and one clear error when the child is gone."""

from __future__ import annotations

import pytest

from ecs_engine.render.assets.lod_worker import LevelBuilder
from ecs_engine.render.assets.mesh_loading import DEFAULT_MODEL, load_mesh
from ecs_engine.render.assets.mesh_lod import build_lods
from ecs_engine.render.assets.primitives import cube_mesh


def test_levels_from_the_child_equal_an_inline_build():
    knot = load_mesh(DEFAULT_MODEL)
    builder = LevelBuilder()
    try:
        builder.submit(7, knot)
        builder.submit(8, cube_mesh())
        assert builder.pending(7) and builder.pending(8)
        got = builder.wait(7)
        assert builder.wait(8) == [] and not builder.pending(7)
    finally:
        builder.close()
    inline = build_lods(knot)
    # the same errors, to the last bits a summation order may move (the H200 host differed by 1 ulp)
    assert [lod.error for lod in got] == pytest.approx([lod.error for lod in inline], rel=1e-12)
    assert [lod.mesh.triangle_count for lod in got] == [lod.mesh.triangle_count for lod in inline]
    assert all(not lod.mesh.positions.flags.writeable and not lod.mesh.indices.flags.writeable for lod in got)


def test_a_child_that_ended_is_one_clear_error():
    builder = LevelBuilder()
    try:
        builder.submit(1, load_mesh(DEFAULT_MODEL))
        assert builder._child is not None
        builder._child.kill()
        with pytest.raises(RuntimeError, match="the child process ended"):
            builder.wait(1)
    finally:
        builder.close()
