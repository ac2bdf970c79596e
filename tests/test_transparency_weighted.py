"""Weighted blended order-independent transparency (render/passes/oit.py, Renderer(transparency=
"weighted")): one layer blends exactly as the sorted path does; two layers of different colours
give the same image whatever their order, McGuire and Bavoil's weighted average (worked out here,
not the sorted blend); layers of one colour match the sorted blend; opaque surfaces in front hide
them; the form is deferred."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu
from test_transparency import CLEAR, FACING_Z, H, W, over, plane, srgb8

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Mesh, Transform
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import plane_mesh


def draw(gpu, world: World, transparency: str = "weighted", **settings) -> tuple[np.ndarray, object]:
    from ecs_engine.render.frame.renderer import Renderer

    world.spawn(Transform(position=(0.0, 0.0, 2.0)), Camera(fov_y=math.radians(40.0), near=0.05))
    renderer = Renderer(
        gpu.device, gpu.target, gpu.meshes, clear_color=tuple(CLEAR), transparency=transparency, **settings
    )
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        form = gpu.target.form
        return gpu.target.pixels()[..., :3].astype(int), form
    finally:
        renderer.destroy()


def test_one_layer_blends_as_the_sorted_path_does():
    with headless_gpu(W, H) as gpu:
        world = World()
        plane(gpu, world, -1.0, (0.2, 0.8, 0.2))
        plane(gpu, world, 0.0, (0.9, 0.1, 0.1), alpha=0.4)
        weighted, form = draw(gpu, world)
    assert form == "deferred"
    expected = srgb8(over((0.9, 0.1, 0.1), 0.4, (0.2, 0.8, 0.2)))
    assert np.abs(weighted[H // 2, W // 2] - expected).max() <= 2


@pytest.mark.parametrize("spawn_order", [(0, 1), (1, 0)])
def test_two_layers_give_one_image_whatever_their_order(spawn_order):
    """Two blended planes of different colours at z = 0 and -0.5 over an opaque one, spawned in
    either order: the weighted image is the same; the sorted blend of one colour is matched."""
    layers = [(0.0, (0.9, 0.1, 0.1)), (-0.5, (0.1, 0.1, 0.9))]
    images = []
    for order in ((0, 1), (1, 0)):
        with headless_gpu(W, H) as gpu:
            world = World()
            plane(gpu, world, -1.0, (0.2, 0.8, 0.2))
            for k in order:
                z, color = layers[k]
                plane(gpu, world, z, color, alpha=0.5)
            images.append(draw(gpu, world)[0])
    assert np.abs(images[0] - images[1]).max() <= 1
    # McGuire and Bavoil's composite, worked out here: the weighted average of the layers over
    # the green by 1 - (1 - 0.5)^2, weights by the distances from the eye (2 and 2.5)
    weights = [0.5 * min(max(10.0 / (1e-5 + (d / 5.0) ** 2 + (d / 200.0) ** 6), 1e-2), 3e3) for d in (2.0, 2.5)]
    average = sum(w * 0.5 * np.array(c) for w, (_, c) in zip(weights, layers)) / sum(w * 0.5 for w in weights)
    expected = srgb8(average * 0.75 + np.array([0.2, 0.8, 0.2]) * 0.25)
    assert np.abs(images[0][H // 2, W // 2] - expected).max() <= 2


def test_same_coloured_layers_match_the_sorted_blend():
    with headless_gpu(W, H) as gpu:
        results = {}
        for mode in ("sorted", "weighted"):
            world = World()
            plane(gpu, world, -1.0, (0.2, 0.8, 0.2))
            for z in (0.0, -0.5):
                plane(gpu, world, z, (0.9, 0.6, 0.1), alpha=0.5)
            results[mode] = draw(gpu, world, mode)[0][H // 2, W // 2]
    assert np.abs(results["weighted"] - results["sorted"]).max() <= 3


def test_an_opaque_surface_in_front_hides_them():
    with headless_gpu(W, H) as gpu:
        world = World()
        plane(gpu, world, -1.0, (0.2, 0.8, 0.2))
        plane(gpu, world, -0.5, (0.9, 0.1, 0.1), alpha=0.5)
        library = materials(world)
        cover = library.add(Material("cover", "unlit", (0.1, 0.1, 0.9, 1.0)))
        world.spawn(
            Transform(position=(0.0, 0.0, 0.0), rotation=FACING_Z, scale=(0.3, 0.3, 0.3)),
            Mesh(handle=gpu.meshes.add(plane_mesh(2.0)), material=cover),
        )
        image, _ = draw(gpu, world)
    assert np.abs(image[H // 2, W // 2] - srgb8((0.1, 0.1, 0.9))).max() <= 1
    assert image[H // 2, W // 4][0] > 60  # beside the cover, the red layer shows


def test_an_unknown_transparency_is_refused():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu, pytest.raises(UsageError, match="transparency"):
        Renderer(gpu.device, gpu.target, gpu.meshes, transparency="depth-peeled")
