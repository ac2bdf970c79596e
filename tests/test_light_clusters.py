"""Clustered lights: cluster.comp's light lists give the same image as the all-lights loop (within
1/255 in 8-bit sRGB), for perspective and orthographic cameras and every render path; the switch
between them follows the light count."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, DirectionalLight, Mesh, PointLight, SpotLight, Transform
from ecs_engine.components.camera import ORTHOGRAPHIC
from ecs_engine.errors import UsageError
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import plane_mesh, sphere_mesh
from ecs_engine.render.layouts import LIGHT_BINS
from ecs_engine.render.lighting.clusters import (
    CLUSTER_MIN_LIGHTS,
    TILE_PX,
    cluster_grid,
    light_census,
    wants_clusters,
)
from ecs_engine.render.lighting.rows import DirectionalLights, PositionalLights

W, H = 160, 96


def lit_field(gpu, lights: int, ortho: bool = False, seed: int = 3) -> World:
    rng = np.random.default_rng(seed)
    world = World()
    library = materials(world)
    floor = library.add(Material("floor", "lambert", (0.6, 0.6, 0.6, 1.0)))
    shiny = library.add(Material("shiny", "cook_torrance", (0.9, 0.5, 0.3, 1.0), metallic=0.2, roughness=0.35))
    world.spawn(Transform(), Mesh(handle=gpu.meshes.add(plane_mesh(30.0, 30)), material=floor))
    ball = gpu.meshes.add(sphere_mesh(24, 12))
    for x in np.linspace(-6, 6, 5):
        for z in np.linspace(-10, 2, 4):
            world.spawn(Transform(position=(x, 0.6, z), scale=(0.6, 0.6, 0.6)), Mesh(handle=ball, material=shiny))
    n_spot = lights // 8
    n_point = lights - n_spot
    world.spawn_batch(
        n_point,
        Transform(
            position=np.c_[rng.uniform(-12, 12, n_point), rng.uniform(0.2, 2.0, n_point), rng.uniform(-20, 4, n_point)]
        ),
        PointLight(
            color=rng.uniform(0.2, 1.0, (n_point, 3)).astype(np.float32),
            intensity=rng.uniform(0.5, 3.0, n_point),
            radius=rng.uniform(0.8, 3.5, n_point),
        ),
    )
    for _ in range(n_spot):
        p = (rng.uniform(-10, 10), rng.uniform(2, 4), rng.uniform(-15, 2))
        world.spawn(
            Transform(position=p, rotation=look_rotation((rng.uniform(-0.3, 0.3), -1.0, rng.uniform(-0.3, 0.3)))),
            SpotLight(color=(1.0, 0.9, 0.7), intensity=8.0, radius=6.0, inner_angle=0.3, outer_angle=0.6),
        )
    world.spawn(Transform(rotation=look_rotation((0.3, -1.0, -0.4))), DirectionalLight(illuminance=0.15))
    world.spawn(Transform(position=(0.0, 6.0, -4.0)), PointLight(intensity=4.0, radius=0.0))  # unbounded
    camera = Camera(fov_y=math.radians(60.0), near=0.1)
    if ortho:
        camera = Camera(projection=ORTHOGRAPHIC, near=0.1, far=100.0, height=14.0)
    world.spawn(Transform(position=(0.0, 5.0, 7.0), rotation=look_rotation((0.0, -0.55, -1.0))), camera)
    return world


def render(gpu, world: World, culling: str, mode: str = "instanced") -> tuple[np.ndarray, bool]:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, light_culling=culling, mode=mode)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].astype(int), renderer.clustered
    finally:
        renderer.destroy()


@pytest.mark.parametrize("ortho", [False, True])
@pytest.mark.parametrize("mode", ["instanced", "indirect"])
@pytest.mark.parametrize("tile", [16, 64])
def test_clustered_lights_draw_what_the_loop_draws(ortho, mode, tile, monkeypatch):
    from ecs_engine.render.lighting import clusters as light_clusters

    monkeypatch.setattr(light_clusters, "TILE_PX", tile)  # 16 (the default): 10 x 6 tiles; 64: 3 x 2
    with headless_gpu(W, H) as gpu:
        world = lit_field(gpu, 300, ortho)
        loop, loop_clustered = render(gpu, world, "loop", mode)
        clustered, was_clustered = render(gpu, world, "clustered", mode)
        dark, _ = render(gpu, lit_field(gpu, 0, ortho), "loop", mode)
    assert not loop_clustered and was_clustered
    assert np.abs(loop - dark).max() > 60  # the small lights make a visible difference
    diff = np.abs(clustered - loop)
    assert diff.max() <= 1, f"max difference {diff.max()} at {np.unravel_index(diff.argmax(), diff.shape)}"


def crowd(gpu, n: int = 300) -> World:
    """n lights on top of each other over the floor: one cluster reaches all of them."""
    world = lit_field(gpu, 0)
    world.spawn_batch(
        n,
        Transform(position=np.tile([0.0, 1.0, 0.0], (n, 1))),
        PointLight(color=(0.02, 0.015, 0.01), intensity=1.0, radius=4.0),
    )
    return world


def frames(gpu, world: World, culling: str, count: int) -> tuple[np.ndarray, object]:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, light_culling=culling)
    try:
        default_schedule().run(world, 0.0)
        for _ in range(count):
            renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].astype(int), renderer.clustered
    finally:
        renderer.destroy()


def test_a_crowd_of_lights_in_one_place_draws_as_the_loop():
    """300 lights on one spot: every tile mask and distance bin there holds all of them (ten mask
    words; no cap per cluster)."""
    with headless_gpu(W, H) as gpu:
        world = crowd(gpu, 300)
        loop, _ = frames(gpu, world, "loop", 1)
        clustered, was_clustered = frames(gpu, world, "clustered", 2)
        dark, _ = frames(gpu, lit_field(gpu, 0), "loop", 1)
    assert was_clustered
    assert np.abs(loop - dark).max() > 30
    assert np.abs(clustered - loop).max() <= 1


@pytest.mark.parametrize("outer", [0.15, 0.6, 0.9, 1.2, math.pi / 2])
def test_spot_cones_of_every_width_draw_as_the_loop(outer, monkeypatch):
    """A spot light's cone is bounded by a tighter sphere than its radius (narrow cones, up to 45
    degrees; wider ones, up to 90, by the sphere around the cap): too tight a sphere would cut the
    light off at tile or bin borders."""
    from ecs_engine.render.lighting import clusters as light_clusters

    monkeypatch.setattr(light_clusters, "TILE_PX", 8)  # many borders
    with headless_gpu(W, H) as gpu:
        world = lit_field(gpu, 0)
        rng = np.random.default_rng(11)
        for _ in range(24):
            p = (rng.uniform(-8, 8), rng.uniform(0.5, 3.0), rng.uniform(-12, 3))
            aim = (rng.uniform(-1, 1), rng.uniform(-1.0, 0.2), rng.uniform(-1, 1))
            world.spawn(
                Transform(position=p, rotation=look_rotation(aim)),
                SpotLight(
                    color=(1.0, 0.8, 0.6),
                    intensity=40.0,
                    radius=rng.uniform(2.0, 7.0),
                    outer_angle=outer,
                    inner_angle=outer * 0.9,
                ),  # bright, with a sharp edge: what a cut-off loses shows
            )
        loop, _ = frames(gpu, world, "loop", 1)
        clustered, was_clustered = frames(gpu, world, "clustered", 1)
    assert was_clustered
    assert np.abs(clustered - loop).max() <= 1


def test_auto_switches_with_the_light_count():
    with headless_gpu(W, H) as gpu:
        _, few_clustered = render(gpu, lit_field(gpu, 8), "auto")
        _, many_clustered = render(gpu, lit_field(gpu, CLUSTER_MIN_LIGHTS + 10), "auto")
    assert not few_clustered and many_clustered
    assert not wants_clusters("auto", False, CLUSTER_MIN_LIGHTS - 1, 0)
    assert wants_clusters("auto", True, CLUSTER_MIN_LIGHTS // 2, 0)  # hysteresis: stays on
    assert not wants_clusters("auto", True, CLUSTER_MIN_LIGHTS // 2 - 1, 0)
    assert not wants_clusters("clustered", False, 10, 10_000)  # the global list would overflow
    assert not wants_clusters("loop", False, 10_000, 0)


def test_census_grid_and_bad_mode():
    parts = [
        PositionalLights(
            np.array([[0.0, 0.0, -10.0], [0.0, 0.0, -1.0]]), np.array([2.0, 0.0]), np.ones((2, 3)), np.ones(2)
        )
    ]
    suns = [DirectionalLights(np.array([[0.0, -1.0, 0.0]]), np.ones((1, 3)), np.ones(1))]
    assert light_census(parts, suns, np.zeros(3)) == (1, 2, pytest.approx(12.0))
    grid = cluster_grid(168, 96, 0.1, 12.0, 33)
    assert (grid.tiles_x, grid.tiles_y, grid.words) == (-(-168 // TILE_PX), -(-96 // TILE_PX), 2)  # last ones partial
    assert grid.near == pytest.approx(0.12)  # s = reach / 100 when that is beyond the near plane
    bins = grid.bin_of(np.array([0.05, 0.12, 0.13, 1.0, 11.99, 1e9]))
    assert bins[0] == bins[1] == 0 and bins[-1] == LIGHT_BINS - 1 and bins[-2] == LIGHT_BINS - 1
    assert (np.diff(bins) >= 0).all()
    assert grid.buffer_bytes == 4 * (grid.masks_start + grid.tiles_x * grid.tiles_y * 2)
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu, pytest.raises(UsageError, match="light culling"):
        Renderer(gpu.device, gpu.target, gpu.meshes, light_culling="tiles")


def test_a_device_without_fragment_subgroups_loops_over_every_light(caplog):
    """Clusters are walked once per subgroup (subgroupMin/Max/Or in the fragment shader): without
    them the renderer keeps the all-lights loop, and says so once when clusters were asked for."""
    import logging

    with headless_gpu(W, H) as gpu, caplog.at_level(logging.WARNING, logger="ecs_engine"):
        assert gpu.device.features["fragmentSubgroupArithmetic"]  # lavapipe and the H100 have them
        gpu.device.features["fragmentSubgroupArithmetic"] = False
        try:
            world = lit_field(gpu, 40)
            loop, _ = frames(gpu, world, "loop", 1)
            image, clustered = frames(gpu, world, "clustered", 2)
        finally:
            gpu.device.features["fragmentSubgroupArithmetic"] = True
    assert not clustered
    assert np.array_equal(image, loop)
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "subgroup" in lines[0]


def test_a_light_grid_larger_than_the_device_binds_keeps_the_loop(caplog):
    """The cluster buffer is one storage binding: past maxStorageBufferRange (a 4K view with tens
    of thousands of lights on some devices) the renderer keeps the loop, and says so once."""
    import logging

    with headless_gpu(W, H) as gpu, caplog.at_level(logging.WARNING, logger="ecs_engine"):
        world = lit_field(gpu, 40)
        from ecs_engine.render.frame.renderer import Renderer

        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, light_culling="clustered")
        try:
            renderer.lights.max_bytes = 1024  # smaller than any grid
            default_schedule().run(world, 0.0)
            for _ in range(2):
                renderer.render(world, readback=True)
            assert not renderer.clustered
        finally:
            renderer.destroy()
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "not clustered" in lines[0]
