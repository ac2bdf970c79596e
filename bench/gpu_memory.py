"""Device memory the renderer's images take, per render configuration, at 1280x720.

What it measures: the bytes of device-local image memory in use (gpu/allocator.py's blocks for
images, DEVICE_LOCAL) after a few frames of the same scene, per configuration: the direct form,
HDR (ACES), HDR with 4x MSAA, HDR with bloom, SSAO and FXAA, deferred lighting, and deferred
with weighted transparency over a blended material. Meshes, textures, shadow maps and the
environment are the same in every configuration of one run, so differences between two trees'
runs of one configuration are what their attachments take (fixed images against the frame
graph's aliased transients). Where the renderer has frame graphs, their transient bytes (aliased
and not) are reported beside.

JSON (schema_version 1): {"benchmark": "gpu-memory", "quick", "machine", "device", "config":
{"scene", "width", "height", "frames"}, "results": [{"config", "image_bytes", "graph_transient_bytes",
"graph_unaliased_bytes", "allocate_calls"}]}.

Standalone, `python3 bench/gpu_memory.py [--size WxH]` measures with whichever ecs_engine is
importable (an older install too, for old/new side by side) and prints one JSON line per
configuration.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterator
from typing import Any

THREADS = 1
SCENE = "grid100"
FRAMES = 4

# name -> (Renderer settings, MSAA samples, whether a blended material is added)
CONFIGS: dict[str, tuple[dict[str, Any], int, bool]] = {
    "direct": ({}, 1, False),
    "hdr": ({"tone_map": "aces"}, 1, False),
    "hdr-msaa4": ({"tone_map": "aces"}, 4, False),
    "hdr-post": ({"tone_map": "aces", "post": ("bloom", "ssao", "fxaa")}, 1, False),
    "deferred": ({"light_culling": "deferred"}, 1, False),
    "deferred-oit": ({"light_culling": "deferred", "transparency": "weighted"}, 1, True),
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--size", default="1280x720", help="WIDTHxHEIGHT of the offscreen target")


def _image_bytes(device: Any) -> tuple[int, int]:
    """(device-local image bytes in use, vkAllocateMemory calls so far)."""
    used = 0
    for (_, kind, where), blocks in device.allocator._blocks.items():
        if kind == "image" and where == "device":
            used += sum(block.used for block in blocks)
    return used, device.allocator.allocate_calls


def _graphs(renderer: Any) -> Iterator[Any]:
    """Every frame graph the renderer holds (none in trees before the frame graph)."""
    from ecs_engine.render.graph import FrameGraph

    seen: set[int] = set()
    todo = [renderer]
    depth = {id(renderer): 0}
    while todo:
        obj = todo.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, FrameGraph):
            yield obj
            continue
        if depth[id(obj)] >= 4 or not hasattr(obj, "__dict__"):
            continue
        for value in vars(obj).values():
            for item in value if isinstance(value, (list, tuple)) else (value,):
                ours = type(item).__module__.startswith("ecs_engine")
                if ours and hasattr(item, "__dict__") and id(item) not in seen:
                    depth[id(item)] = depth[id(obj)] + 1
                    todo.append(item)


def measure(name: str, width: int, height: int, frames: int) -> dict[str, Any]:
    from ecs_engine import World
    from ecs_engine.app.scenes import default_schedule, scene_builder
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance
    from ecs_engine.gpu.offscreen import OffscreenTarget

    try:
        from ecs_engine.render.assets.materials import Material, materials
        from ecs_engine.render.assets.mesh_registry import MeshRegistry
        from ecs_engine.render.frame.renderer import Renderer
    except ImportError:  # an older tree, before render/ had sub-packages (old against new)
        from ecs_engine.render.materials import Material, materials  # type: ignore[no-redef]
        from ecs_engine.render.mesh_registry import MeshRegistry  # type: ignore[no-redef]
        from ecs_engine.render.renderer import Renderer  # type: ignore[no-redef]

    settings, samples, blended = CONFIGS[name]
    instance = Instance()
    device = Device(instance)
    target = OffscreenTarget(device, width, height, samples=samples)
    meshes = MeshRegistry(device)
    renderer = None
    try:
        world = World()
        scene_builder(SCENE)(world, meshes.add)
        if blended:
            from ecs_engine.components import Mesh

            glass = materials(world).add(Material(base_color=(0.2, 0.6, 1.0, 0.4), alpha_mode="blend"))
            for batch in world.query(Mesh):
                batch[Mesh].material[: max(1, len(batch) // 4)] = glass
                break
        before, _ = _image_bytes(device)
        renderer = Renderer(device, target, meshes, **settings)
        schedule = default_schedule()
        for _ in range(frames):
            schedule.run(world, 1 / 60)
            renderer.render(world)
        device.wait_idle()
        used, calls = _image_bytes(device)
        graphs = list(_graphs(renderer))
        return {
            "config": name,
            "image_bytes": used,
            "renderer_image_bytes": used - before,
            "graph_transient_bytes": sum(g.transient_bytes for g in graphs) if graphs else None,
            "graph_unaliased_bytes": sum(g.unaliased_bytes for g in graphs) if graphs else None,
            "allocate_calls": calls,
            "form": getattr(target, "form", None),
            "device": device.info.name,
        }
    finally:
        if renderer is not None:
            renderer.destroy()
        meshes.destroy()
        target.destroy()
        device.destroy()
        instance.destroy()


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    width, height = (int(v) for v in args.size.lower().split("x"))
    if args.quick:
        width, height = 160, 90
    results = []
    progress.total = len(CONFIGS)
    for name in CONFIGS:
        with progress.step(f"{name} at {width}x{height}"):
            results.append(measure(name, width, height, FRAMES))
    device = results[0].pop("device")
    for r in results[1:]:
        r.pop("device")
    print(f"{'config':>13} {'form':>9} {'image MiB':>10} {'renderer MiB':>13} {'graph MiB':>10}")
    for r in results:
        graph = "-" if r["graph_transient_bytes"] is None else f"{r['graph_transient_bytes'] / 2**20:.1f}"
        print(
            f"{r['config']:>13} {r['form']!s:>9} {r['image_bytes'] / 2**20:10.1f} "
            f"{r['renderer_image_bytes'] / 2**20:13.1f} {graph:>10}"
        )
    return {
        "benchmark": "gpu-memory",
        "schema_version": 1,
        "quick": bool(args.quick),
        "machine": machine,
        "device": device,
        "config": {"scene": SCENE, "width": width, "height": height, "frames": FRAMES},
        "results": results,
    }


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    add_arguments(parser)
    parser.add_argument("--only", default=None, help="one configuration's name")
    a = parser.parse_args()
    w, h = (int(v) for v in a.size.lower().split("x"))
    for config in [a.only] if a.only else list(CONFIGS):
        print(json.dumps(measure(config, w, h, FRAMES)), flush=True)
    sys.exit(0)
