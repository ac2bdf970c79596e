"""What the per-frame path keeps between frames (issue 17's 1-cube CPU frame): each kept thing
must follow the change that would make it stale."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import shared_device

from ecs_engine import World
from ecs_engine.components import Transform, Velocity
from ecs_engine.errors import UsageError
from ecs_engine.render.extract.frame_data import CULLING, check_culling


def test_buffer_views_are_kept_per_shape_and_follow_the_buffer():
    from ecs_engine.gpu.memory import HOST, Buffer

    device = shared_device()
    vk = device.vk
    buffer = Buffer(device, 256, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, HOST)
    try:
        floats = buffer.array(np.float32, 8)
        assert buffer.array(np.float32, 8) is floats  # kept
        assert buffer.array(np.float32, [8]) is buffer.array(np.float32, (8,))  # a list shape is a tuple's
        floats[:] = np.arange(8)
        assert buffer.array(np.float32, 4, offset=16).tolist() == [4, 5, 6, 7]  # the same mapped bytes
        assert buffer.array(np.float32).shape == (64,)  # shape None: the whole buffer
        for n in range(1, 40):  # shapes that come and go are not kept forever
            buffer.array(np.float32, n)
        assert len(buffer._views) <= 16
        bigger = buffer.grown(1024)
        assert bigger is not buffer and bigger.array(np.float32).shape == (256,)
        assert buffer._views == {}  # destroyed by grown: nothing kept over freed memory
        buffer = bigger
    finally:
        buffer.destroy()


def test_check_culling_fast_path_agrees_with_the_checks():
    for name in CULLING:
        assert check_culling(name, None) == name  # extract's call: any method, the path decides
        assert check_culling(name, "indirect" if name == "occlusion" else "instanced") == name
    assert check_culling(True) == "frustum" and check_culling(False) == "none"
    assert check_culling("frustum", "indirect") == "frustum"
    with pytest.raises(UsageError, match="indirect"):
        check_culling("temporal", "indirect")
    with pytest.raises(UsageError, match="needs --mode indirect"):
        check_culling("occlusion", "instanced")
    with pytest.raises(UsageError, match="unknown culling"):
        check_culling("sometimes")


def test_changed_filter_columns_kept_per_filter_still_follow_writes():
    """Query.iter(changed=...) keeps the filter's columns; which tables pass still follows writes."""
    world = World()
    a = world.spawn(Transform(), Velocity(linear=(1.0, 0.0, 0.0)))
    world.spawn(Transform())
    query = world.query(Transform, write=())
    since = world.tick
    assert [len(b) for b in query.iter(changed=(Velocity,), since=since)] == []
    world.set(a, Velocity, linear=(2.0, 0.0, 0.0))
    assert [len(b) for b in query.iter(changed=(Velocity,), since=since)] == [1]  # the Velocity table only
    assert [len(b) for b in query.iter(changed=(Velocity,), since=world.tick)] == []
    assert sorted(len(b) for b in query.iter(changed=[Transform], since=-1)) == [1, 1]  # a list works too


def test_frame_slots_know_their_index():
    from ecs_engine.gpu.frames import FrameRing

    ring = FrameRing(shared_device())
    try:
        assert [f.slot for f in ring.frames] == list(range(len(ring.frames)))
    finally:
        ring.destroy()
