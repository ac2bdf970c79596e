"""The session: one owner for each setting, live changes without rebuilding what stays, and a
clean teardown when it cannot be built."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from golden_images import SIZE, image_difference

from ecs_engine.app.offscreen import OffscreenSource
from ecs_engine.app.session import Session
from ecs_engine.app.settings import RunOptions
from ecs_engine.errors import UsageError
from ecs_engine.jobs import JobPool


def options(**kw) -> RunOptions:
    return RunOptions(**{"scene": "grid100", "width": SIZE[0], "height": SIZE[1], "validate": True, "threads": 2, **kw})


def draw(session: Session) -> np.ndarray:
    session.schedule.run(session.world, 0.0)
    session.renderer.render(session.world, readback=True)
    return session.gpu.target.pixels()


def test_every_path_and_recorder_draws_the_same_image_in_one_renderer():
    source = OffscreenSource()
    with Session(options(recorder="python"), source) as session:
        renderer, frames = session.renderer, session.renderer.frames
        reference = draw(session)
        assert reference[..., :3].max() > 30
        seen = {id(renderer.path)}
        for mode, recorder in [
            ("instanced", "native"),
            ("per_entity", "python"),
            ("per_entity", "native"),
            ("indirect", "native"),
            ("instanced", "python"),
        ]:
            if recorder == "native":
                pytest.importorskip("numba")
            session.apply(replace(session.settings, mode=mode, recorder=recorder))
            assert (renderer.mode, session.settings.recorder) == (mode, recorder)
            assert session.renderer is renderer and renderer.frames is frames  # only the path changed
            seen.add(id(renderer.path))
            mean, outliers = image_difference(draw(session), reference)
            assert mean < 0.05 and outliers == 0, (mode, recorder)
        assert len(seen) == 6
    assert source.validation_messages() == []


def test_settings_are_read_from_their_owners():
    source = OffscreenSource()
    with Session(options(), source) as session:
        assert session.world.resources[JobPool] is session.pool
        session.pool.resize(3)  # changed at the owner: the settings say so
        assert session.settings.threads == 3
        session.renderer.culling = "none"
        assert session.settings.culling == "none"
        assert session.settings.present is None  # headless: no swapchain
        wanted = session.settings
        wanted.scene, wanted.threads = "cube", 1
        worlds = []
        session.on_world.append(worlds.append)
        session.apply(wanted)
        assert worlds == [session.world] and session.settings.scene == "cube"
        assert session.pool.threads == 1 and session.world.resources[JobPool] is session.pool
        assert draw(session)[..., :3].max() > 30
    assert source.validation_messages() == []


def test_a_session_that_cannot_be_built_closes_what_it_opened():
    source = OffscreenSource()
    with pytest.raises(UsageError, match="unknown scene 'nope'"):
        Session(options(scene="nope"), source)
    assert source.validation_messages() == []  # and conftest finds no GPU memory left allocated


def test_resizing_the_pool_frees_the_old_threads_command_pools():
    source = OffscreenSource()
    with Session(options(scene="grid100", chunk_rows=16), source) as session:
        draw(session)
        draw(session)
        before = session.renderer.secondaries.pool_count()
        for threads in (4, 3, 4, 2):
            session.apply(replace(session.settings, threads=threads))
            draw(session)
            draw(session)
        # per frame slot at most one pool per thread that ran jobs (the caller's included)
        assert session.renderer.secondaries.pool_count() <= max(before, 2 * 2)
    assert source.validation_messages() == []


def test_switching_paths_keeps_nothing_of_the_old_ones():
    pytest.importorskip("numba")
    source = OffscreenSource()
    with Session(options(), source) as session:
        for mode in ("per_entity", "instanced", "per_entity", "instanced") * 2:
            session.apply(replace(session.settings, mode=mode, recorder="native"))
            draw(session)
            draw(session)
        target = session.gpu.target
        state = session.renderer.target_state(target.framebuffer, target.width, target.height).path_state
        assert len(state) == 2  # the path in use keeps one per frame slot; the old paths' are gone


def test_fill_changes_live_and_a_bad_one_changes_nothing():
    source = OffscreenSource()
    with Session(options(fill="wireframe"), source) as session:
        assert session.settings.fill == "wireframe"
        wire = draw(session)[..., :3].copy()
        session.apply(replace(session.settings, fill="solid"))
        assert session.settings.fill == "solid" and session.renderer.fill == "solid"
        solid = draw(session)[..., :3]
        assert (solid != wire).any()
        with pytest.raises(UsageError, match="unknown fill"):
            session.apply(replace(session.settings, fill="dots", scene="cube", threads=1))
        assert session.settings.scene == "grid100" and session.pool.threads == 2  # all or nothing
    assert source.validation_messages() == []
