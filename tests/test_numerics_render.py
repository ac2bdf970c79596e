"""Rendering in the numerical corners (lavapipe, validation on): far from the origin,
near-coincident surfaces under reverse-Z, degenerate transforms, and extreme lights."""

from __future__ import annotations

import math

import numpy as np
import pytest
from golden_images import image_difference
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import (
    Camera,
    Mesh,
    ModelMatrix,
    NormalMatrix,
    PointLight,
    RenderOrigin,
    Transform,
)
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.draw.instance_rows import INSTANCE_DTYPE, write_rows

W, H = 160, 120


def render(gpu, world: World, frames: int = 1) -> np.ndarray:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
    try:
        schedule = default_schedule()
        for _ in range(frames):
            schedule.run(world, 0.0)
            renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].copy()
    finally:
        renderer.destroy()


def cube_scene(gpu, offset: np.ndarray, pinned_origin: bool = False) -> World:
    """Two cubes, a light and a camera, all shifted by `offset`."""
    world = World()
    cube = gpu.meshes.add(cube_mesh())
    world.spawn(Transform(position=offset + (-0.6, 0.0, 0.0), rotation=(0.2, 0.3, 0.1, 0.9)), Mesh(handle=cube))
    world.spawn(Transform(position=offset + (0.7, 0.1, -0.4), scale=(0.6, 1.2, 0.6)), Mesh(handle=cube, material=2))
    world.spawn(Transform(position=offset + (1.0, 2.0, 2.5)), PointLight(intensity=12.0, radius=0.0))
    add_camera(world, eye=tuple(offset + (0.4, 0.9, 3.0)), target=tuple(offset))
    if pinned_origin:  # classic float32 world-space rendering, for comparison
        world.resources[RenderOrigin] = RenderOrigin(np.zeros(3), follow_camera=False)
    return world


@pytest.mark.parametrize("distance", [1e6, 1e7])
def test_far_from_the_origin_looks_the_same_camera_relative(distance):
    offset = np.array([distance, -0.3 * distance, 0.7 * distance])
    with headless_gpu(W, H) as gpu:
        at_origin = render(gpu, cube_scene(gpu, np.zeros(3)))
        far = render(gpu, cube_scene(gpu, offset))
        pinned = render(gpu, cube_scene(gpu, offset, pinned_origin=True))
    assert at_origin.max() > 60  # something lit
    mean, outliers = image_difference(far, at_origin)
    assert mean <= 1.5 and outliers <= 0.005  # the golden tolerance
    mean, outliers = image_difference(pinned, at_origin)
    assert mean > 1.5 or outliers > 0.005  # float32 world space cannot hold it


def test_pinned_origin_at_the_origin_matches_camera_relative():
    """The pinned path itself is right: near the origin both agree."""
    with headless_gpu(W, H) as gpu:
        relative = render(gpu, cube_scene(gpu, np.array([3.0, 1.0, -2.0])))
        pinned = render(gpu, cube_scene(gpu, np.array([3.0, 1.0, -2.0]), pinned_origin=True))
    mean, outliers = image_difference(pinned, relative)
    assert mean <= 0.5 and outliers <= 0.001


@pytest.mark.parametrize("far", [1e6, math.inf])
def test_surfaces_1e4_of_the_distance_apart_resolve_under_reverse_z(far):
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        world = World()
        d = 1000.0
        # the farther (blue) wall is drawn first: had the depths collapsed to one value, the
        # nearer (red) one would fail GREATER and blue would show
        for distance, material in ((d * (1 + 1e-4), 2), (d, 1)):
            world.spawn(
                Transform(position=(0.0, 0.0, -distance - 5.0), scale=(4000.0, 4000.0, 10.0)),
                Mesh(handle=cube, material=material),
            )
        world.spawn(Transform(position=(0.0, 0.0, -900.0)), PointLight(intensity=3e3, radius=0.0))
        world.spawn(Transform(), Camera(fov_y=math.radians(40.0), near=0.01, far=far))
        pixels = render(gpu, world).astype(int)
    centre = pixels[H // 2 - 10 : H // 2 + 10, W // 2 - 10 : W // 2 + 10].reshape(-1, 3)
    assert (centre[:, 0] > centre[:, 2] + 20).all()  # red in front everywhere


def test_degenerate_transforms_reach_the_gpu_finite():
    from ecs_engine.systems import TransformSystem

    world = World()
    scales = [(0, 0, 0), (0, 1, 1), (-1, 1, 1), (-1, -1, -1), (1e30, 1e30, 1e30), (1e-30, 1, 1), (1e30, 1e-30, 1)]
    quats = [
        (0, 0, 0, 5.0),
        (1e-12, 0, 0, 1e-12),
        (3, -4, 0, 0),
        (0.1, 0.2, 0.3, 0.4),
        (0, 0, 0, 1),
        (1, 1, 1, 1),
        (0, 1e-6, 0, 1e-6),
    ]
    world.spawn_batch(
        len(scales),
        Transform(
            position=np.full((len(scales), 3), 1e30), rotation=np.array(quats), scale=np.array(scales, dtype=float)
        ),
        Mesh(handle=0),
        NormalMatrix(),
    )
    world.run_system(TransformSystem(), 0.0)
    for batch in world.query(ModelMatrix, NormalMatrix, Mesh, write=()):
        m = batch[ModelMatrix]
        assert np.isfinite(m.model).all() and np.isfinite(batch[NormalMatrix].normal).all()
        rows = np.zeros(len(batch), INSTANCE_DTYPE)
        n = write_rows(
            m.model,
            batch[Mesh].handle,
            batch[Mesh].material,
            np.zeros((1, 3)),
            np.ones(1),
            None,
            6,
            rows,
            np.zeros(2, np.int64),
        )
        assert n == len(batch)
        assert np.isfinite(rows["model"]).all()


@pytest.mark.parametrize("field, bad", [("position", 1e31), ("scale", -2e30), ("position", math.nan)])
def test_transforms_beyond_float32_reach_are_rejected(field, bad):
    world = World()
    value = np.zeros(3) if field == "position" else np.ones(3)
    value[1] = bad
    with pytest.raises(ValueError, match=f"Transform.{field}"):
        world.spawn(Transform(**{field: value}))


def test_a_quaternion_too_short_to_normalise_is_rejected():
    with pytest.raises(ValueError, match=r"Transform\.rotation must have non-zero length"):
        World().spawn(Transform(rotation=(0.0, 1e-300, 0.0, 1e-300)))


def test_extreme_lights_give_finite_bright_colours():
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        world = World()
        world.spawn(Transform(scale=(2.0, 2.0, 2.0)), Mesh(handle=cube))
        add_camera(world, eye=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0))
        reference = render(gpu, world)
        # on the face the camera sees (z = 1): a light exactly at a fragment, one of radius 0,
        # one of intensity 0, 1,000 of the largest float32 intensity on one spot in front of
        # the face, and 1,000 just behind it (their energy overflows where the diffuse term
        # is 0: inf * 0 would be NaN)
        world.spawn(Transform(position=(0.0, 0.0, 1.0)), PointLight(intensity=1.0, radius=0.0))
        world.spawn(Transform(position=(0.3, 0.3, 1.0)), PointLight(intensity=0.0, radius=5.0))
        for z in (1.01, 0.999):
            world.spawn_batch(
                1000,
                Transform(position=np.tile([-0.4, -0.3, z], (1000, 1))),
                PointLight(intensity=np.float32(3.0e38), radius=0.0),
            )
        lit = render(gpu, world).astype(int)
    cube_mask = reference.max(axis=2) > 3  # where the cube is (ambient light only)
    assert cube_mask.mean() > 0.1
    # a NaN would come out black: every cube pixel is at least as bright as with ambient alone
    assert (lit[cube_mask].max(axis=1) >= reference[cube_mask].max(axis=1) - 2).all()
    assert lit.max() >= 250  # and the huge lights saturate instead of overflowing


@pytest.mark.parametrize("scale", [(1e-30, 1.0, 1.0), (0.0, 1.0, 1.0), (3.0, 1e-20, 1.0), (50.0, 1.0, 1e-3)])
def test_tiny_flat_and_stretched_scales_shade_without_holes(scale):
    """The vertex shader's normal matrix (cofactor of the columns scaled by the largest) stays
    finite: a cube 1e-30 thin, flattened to nothing, or stretched, draws without black (NaN)
    pixels. (Geometry 1e30 wide is beyond what a rasteriser clips reliably, so the huge end is
    covered by the matrices' test above.)"""
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        world = World()
        world.spawn(Transform(scale=scale, rotation=(0.0, 0.38, 0.0, 0.92)), Mesh(handle=cube))
        world.spawn(Transform(position=(1.0, 2.0, 2.5)), PointLight(intensity=12.0, radius=0.0))
        add_camera(world, eye=(0.4, 0.9, 3.0), target=(0.0, 0.0, 0.0))
        pixels = render(gpu, world).astype(int)
        world.destroy(world.query(Mesh, write=()).entities())
        background = render(gpu, world).astype(int)
    drawn = np.abs(pixels - background).max(axis=2) > 0
    assert drawn.sum() > 50  # the slab is on screen
    assert (pixels[drawn].max(axis=1) > 8).all()  # and every pixel of it is lit, none black
