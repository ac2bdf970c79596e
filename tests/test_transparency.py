"""Alpha-blended materials: drawn after the opaque ones, sorted back to front whatever the spawn
order, blended over what is behind them (each checked against the blend computed in NumPy), hidden
by opaque objects in front, in every render path."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Mesh, Transform
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import plane_mesh
from ecs_engine.render.assets.textures import linear_to_srgb

W, H = 64, 48
FACING_Z = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))
CLEAR = np.array([0.0, 0.0, 0.0])


def plane(gpu, world, z: float, color, alpha: float = 1.0, size: float = 2.0) -> None:
    library = materials(world)
    mode = "blend" if alpha < 1.0 else "opaque"
    m = library.add(Material(f"p{z}", "unlit", (*color, alpha), alpha_mode=mode))
    world.spawn(
        Transform(position=(0.0, 0.0, z), rotation=FACING_Z), Mesh(handle=gpu.meshes.add(plane_mesh(size)), material=m)
    )


def draw(gpu, world: World, mode: str) -> tuple[np.ndarray, object]:
    from ecs_engine.render.frame.renderer import Renderer

    world.spawn(Transform(position=(0.0, 0.0, 2.0)), Camera(fov_y=math.radians(40.0), near=0.05))
    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode=mode, clear_color=tuple(CLEAR))
    try:
        default_schedule().run(world, 0.0)
        stats = renderer.render(world, readback=True)
        return gpu.target.pixels()[H // 2, W // 2, :3].astype(int), stats
    finally:
        renderer.destroy()


def srgb8(linear) -> np.ndarray:
    return np.round(linear_to_srgb(np.asarray(linear, float)) * 255)


def over(color, alpha, below) -> np.ndarray:
    return alpha * np.asarray(color, float) + (1 - alpha) * np.asarray(below, float)


MODES = ["instanced", "per_entity", "indirect"]


@pytest.mark.parametrize("mode", MODES)
def test_a_blended_plane_over_an_opaque_one(mode):
    with headless_gpu(W, H) as gpu:
        world = World()
        plane(gpu, world, 0.3, (0.0, 1.0, 0.0), alpha=0.25)  # spawned first, drawn last
        plane(gpu, world, -0.5, (1.0, 0.0, 0.0))
        got, stats = draw(gpu, world, mode)
    want = srgb8(over((0.0, 1.0, 0.0), 0.25, (1.0, 0.0, 0.0)))
    assert np.abs(got - want).max() <= 1, (got, want)
    assert stats.instances == 2


@pytest.mark.parametrize("mode", MODES)
def test_blended_planes_are_sorted_back_to_front(mode):
    """Spawned front first: unsorted, the back plane would blend over the front one."""
    with headless_gpu(W, H) as gpu:
        world = World()
        plane(gpu, world, 0.5, (0.0, 1.0, 0.0), alpha=0.5)
        plane(gpu, world, 0.0, (0.0, 0.0, 1.0), alpha=0.5)
        plane(gpu, world, -0.5, (1.0, 0.0, 0.0), alpha=0.5)
        got, _ = draw(gpu, world, mode)
    want = srgb8(over((0, 1, 0), 0.5, over((0, 0, 1), 0.5, over((1, 0, 0), 0.5, CLEAR))))
    wrong = srgb8(over((1, 0, 0), 0.5, over((0, 0, 1), 0.5, over((0, 1, 0), 0.5, CLEAR))))
    assert np.abs(got - want).max() <= 1, (got, want)
    assert np.abs(want - wrong).max() > 40  # the order shows


def test_an_opaque_plane_in_front_hides_a_blended_one():
    with headless_gpu(W, H) as gpu:
        world = World()
        plane(gpu, world, -0.5, (0.0, 1.0, 0.0), alpha=0.5)
        plane(gpu, world, 0.3, (1.0, 0.0, 0.0))
        got, _ = draw(gpu, world, "instanced")
    assert tuple(got) == (255, 0, 0)


def test_switching_a_material_to_blend_and_back():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = World()
        plane(gpu, world, 0.3, (0.0, 1.0, 0.0))
        plane(gpu, world, -0.5, (1.0, 0.0, 0.0))
        world.spawn(Transform(position=(0.0, 0.0, 2.0)), Camera(fov_y=math.radians(40.0), near=0.05))
        library = materials(world)
        front = len(library) - 2
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, clear_color=(0.0, 0.0, 0.0))
        try:
            default_schedule().run(world, 0.0)
            seen = []
            for changes in ({}, {"alpha_mode": "blend", "base_color": (0.0, 1.0, 0.0, 0.5)}, {"alpha_mode": "opaque"}):
                if changes:
                    library.update(front, **changes)
                renderer.render(world, readback=True)
                seen.append(tuple(gpu.target.pixels()[H // 2, W // 2, :3]))
        finally:
            renderer.destroy()
    assert seen[0] == (0, 255, 0) and seen[2] == (0, 255, 0)
    assert np.abs(np.array(seen[1]) - srgb8(over((0, 1, 0), 0.5, (1, 0, 0)))).max() <= 1
