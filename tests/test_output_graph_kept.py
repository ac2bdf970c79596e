"""The output graph's kept slots (render/passes/output_graph.py `_kept`: per frame slot, the
graph its last full prepare made and the imports then) forget a graph when it is destroyed: a
swapchain's recreation or a new shape remakes the graphs, and no slot holds a destroyed one."""

from __future__ import annotations

from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, PointLight, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.assets.primitives import cube_mesh


def test_a_rebuild_leaves_no_slot_keeping_a_destroyed_graph():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(32, 24) as gpu:
        world = World()
        world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
        world.spawn(Transform(position=(2.0, 3.0, 3.0)), PointLight(intensity=8.0))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        default_schedule().run(world, 0.0)
        slots = len(renderer.frames.frames)
        for _ in range(slots):
            renderer.render(world)
        output = renderer.output.graph
        (first,) = output.graphs.values()
        assert len(output._kept) == slots > 1 and all(kept[2] is first for kept in output._kept.values())
        gpu.target.recreations = getattr(gpu.target, "recreations", 0) + 1  # as a new swapchain does
        renderer.render(world)  # one slot's frame: the graphs are made again
        (second,) = output.graphs.values()
        assert second is not first and first.compiled is None  # destroyed
        assert [kept[2] for kept in output._kept.values()] == [second]  # the other slots' went with it
        for _ in range(slots):
            renderer.render(world)
        assert len(output._kept) == slots and all(kept[2] is second for kept in output._kept.values())
        output.destroy()
        assert output._kept == {} and output.graphs == {}
