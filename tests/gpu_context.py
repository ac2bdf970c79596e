"""One validated Vulkan instance and device for the whole test run, and what tests draw with.

Every test that renders headless shares them (conftest.py hands them to each OffscreenSource and
checks, around each test, that no validation message arrived and no GPU memory stayed
allocated): NVIDIA's driver refuses new instances after about 30 in one process, which the
suite passes by far. `headless_gpu()` gives a test its own target and meshes on that device."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

_shared: list[Any] = []  # [instance, device] once made


def shared_device() -> Any:
    """The run's device, made on first use (a run of CPU-only tests makes none)."""
    if not _shared:
        from ecs_engine.gpu.device import Device
        from ecs_engine.gpu.instance import Instance

        instance = Instance(validate=True)
        _shared.extend([instance, Device(instance)])
    return _shared[1]


def shared_instance() -> Any | None:
    return _shared[0] if _shared else None


def close_shared() -> None:
    if _shared:
        instance, device = _shared
        device.destroy()
        instance.destroy()
        _shared.clear()
        assert instance.messages == [], instance.messages  # leaks are reported at destroy


@dataclass
class Gpu:
    instance: Any
    device: Any
    target: Any
    meshes: Any
    owned: list[Any] = field(default_factory=list)  # destroyed first, last added first


@contextmanager
def headless_gpu(width: int = 64, height: int = 48) -> Iterator[Gpu]:
    from ecs_engine.gpu.offscreen import OffscreenTarget
    from ecs_engine.render.assets.mesh_registry import MeshRegistry

    device = shared_device()
    gpu = Gpu(device.instance, device, OffscreenTarget(device, width, height), MeshRegistry(device))
    try:
        yield gpu
    finally:
        for obj in reversed(gpu.owned):
            (obj.destroy if hasattr(obj, "destroy") else obj.close)()
        gpu.meshes.destroy()
        gpu.target.destroy()


def render_world(gpu: Gpu, world: Any, target: Any = None, frames: int = 1, **settings: Any) -> Any:
    """`world` drawn by a new Renderer (settings: its keyword arguments) after one run of the
    default schedule: the RGB pixels (height, width, 3) as int64 of the last of `frames` frames."""
    import numpy as np

    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    target = target or gpu.target
    renderer = Renderer(gpu.device, target, gpu.meshes, **settings)
    try:
        default_schedule().run(world, 0.0)
        for _ in range(frames):
            renderer.render(world, readback=True)
        return target.pixels()[..., :3].astype(np.int64)
    finally:
        renderer.destroy()
