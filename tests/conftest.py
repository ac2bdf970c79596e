"""The test run's shared Vulkan device (see gpu_context.py) and the checks around every test:
no validation message, no GPU memory left allocated, the device's feature flags as they were."""

from __future__ import annotations

import pytest
from gpu_context import close_shared, shared_device, shared_instance

from ecs_engine.app.offscreen import sharing
from ecs_engine.render.graph import FrameGraph

# every compile calls each pass's setup and fails where a pass's declares() hid a change
FrameGraph.verify_declares = True


@pytest.fixture(autouse=True)
def config_home(tmp_path_factory):
    """The user's config folder (the editor's layout, settings), empty for each test: tests
    never read or write the real one, nor see what another test left. Subprocesses inherit it.
    (Not through `monkeypatch`: that would keep the test's own monkeypatch alive past the GPU
    checks below, which must see the device's features restored.)"""
    import os

    path = tmp_path_factory.mktemp("config")
    old = os.environ.get("XDG_CONFIG_HOME")
    os.environ["XDG_CONFIG_HOME"] = str(path)
    yield path
    if old is None:
        os.environ.pop("XDG_CONFIG_HOME", None)
    else:
        os.environ["XDG_CONFIG_HOME"] = old


@pytest.fixture(scope="session", autouse=True)
def one_vulkan_device():
    with sharing(shared_device):
        yield
    close_shared()


@pytest.fixture(autouse=True)
def gpu_left_as_found():
    instance = shared_instance()
    before = _state() if instance is not None else None
    yield
    instance = shared_instance()
    if instance is None:
        return
    after = _state()
    if before is None:  # the device was made during this test
        before = (0, 0, after[2])
    assert instance.messages[before[0] :] == [], "validation messages during this test"
    assert after[1] == before[1], f"{after[1] - before[1]} bytes of GPU memory still allocated after the test"
    assert after[2] == before[2], "the test changed the shared device's feature flags"


def _state() -> tuple[int, int, dict[str, bool]]:
    device = shared_device()
    return len(device.instance.messages), device.allocator.stats()["used_bytes"], dict(device.features)


@pytest.fixture
def scene():
    """The editor on a headless grid100 session, driven frame by frame (test_editor.Scene)."""
    from test_editor import Scene

    s = Scene()
    try:
        yield s
    finally:
        s.close()
