"""A validated headless device for tests that drive the renderer directly; on exit everything
is destroyed and any validation message fails the test."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any


@dataclass
class Gpu:
    instance: Any
    device: Any
    target: Any
    meshes: Any
    owned: list[Any] = field(default_factory=list)  # destroyed first, last added first


@contextmanager
def headless_gpu(width: int = 64, height: int = 48) -> Iterator[Gpu]:
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance
    from ecs_engine.gpu.offscreen import OffscreenTarget
    from ecs_engine.render.mesh_registry import MeshRegistry

    instance = Instance(validate=True)
    device = Device(instance)
    gpu = Gpu(instance, device, OffscreenTarget(device, width, height), MeshRegistry(device))
    try:
        yield gpu
    finally:
        for obj in reversed(gpu.owned):
            (obj.destroy if hasattr(obj, "destroy") else obj.close)()
        gpu.meshes.destroy()
        gpu.target.destroy()
        device.destroy()
        instance.destroy()
    assert instance.messages == []
