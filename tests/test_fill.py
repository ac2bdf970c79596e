"""--fill: meshes as solid triangles, wireframe edges or vertex points, on devices that allow it;
a device without fillModeNonSolid gets one clear refusal; the editor's setting switches it live."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Mesh, PointLight, Transform
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.primitives import sphere_mesh

W, H = 96, 96


def covered(gpu, fill: str) -> int:
    """Pixels not the clear colour, drawing a sphere with `fill`."""
    from ecs_engine.render.frame.renderer import Renderer

    world = World()
    world.spawn(Transform(), Mesh(handle=gpu.meshes.add(sphere_mesh(12, 6)), material=0))
    world.spawn(Transform(position=(0.0, 0.0, 3.0)), Camera(fov_y=math.radians(50.0)))
    world.spawn(Transform(position=(2.0, 2.0, 3.0)), PointLight(intensity=20.0))
    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, fill=fill)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        img = gpu.target.pixels()[..., :3].astype(int)
        return int((np.abs(img - img[0, 0]).sum(-1) > 12).sum())
    finally:
        renderer.destroy()


def test_wireframe_and_points_cover_less_than_solid():
    with headless_gpu(W, H) as gpu:
        solid, wire, points = (covered(gpu, fill) for fill in ("solid", "wireframe", "points"))
    # measured on lavapipe: 892, 451 and 37 pixels of 9,216 (a 12 x 6 sphere: 62 vertices, some hidden)
    assert solid > 800
    assert 150 < wire < 0.7 * solid
    assert 15 < points < 0.2 * wire


def test_a_device_without_non_solid_fill_refuses_it(monkeypatch):
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        monkeypatch.setitem(gpu.device.features, "fillModeNonSolid", False)
        with pytest.raises(UsageError, match="fillModeNonSolid"):
            Renderer(gpu.device, gpu.target, gpu.meshes, fill="wireframe")
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            with pytest.raises(UsageError, match="fillModeNonSolid"):
                renderer.set_fill("points")
            assert renderer.fill == "solid"
            with pytest.raises(UsageError, match="unknown fill"):
                renderer.set_fill("dots")
        finally:
            renderer.destroy()


def test_cli_fill_flag(tmp_path):
    shot = tmp_path / "wire.png"
    base = [sys.executable, "-m", "ecs_engine", "demo", "grid100", "--headless", "--frames", "2"]
    proc = subprocess.run(
        [*base, "--width", "64", "--height", "48", "--fill", "wireframe", "--validate", "--screenshot", str(shot)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert shot.exists()
    bad = subprocess.run([*base, "--fill", "dots"], capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "--fill" in bad.stderr and "Traceback" not in bad.stderr


def two_spheres(gpu, left_fill: str) -> np.ndarray:
    """Two spheres of one mesh: the left with a material of fill `left_fill`, the right solid."""
    from ecs_engine.render.assets.materials import Material, materials
    from ecs_engine.render.frame.renderer import Renderer

    world = World()
    mesh = gpu.meshes.add(sphere_mesh(12, 6))
    library = materials(world)
    left = library.add(Material("left", "lambert", fill=left_fill))
    right = library.add(Material("right", "lambert"))
    world.spawn(Transform(position=(-1.1, 0.0, 0.0)), Mesh(handle=mesh, material=left))
    world.spawn(Transform(position=(1.1, 0.0, 0.0)), Mesh(handle=mesh, material=right))
    world.spawn(Transform(position=(0.0, 0.0, 3.2)), Camera(fov_y=math.radians(55.0)))
    world.spawn(Transform(position=(2.0, 2.0, 4.0)), PointLight(intensity=30.0))
    renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        img = gpu.target.pixels()[..., :3].astype(int)
        return np.abs(img - img[0, 0]).sum(-1) > 12
    finally:
        renderer.destroy()


def test_a_material_with_its_own_fill():
    with headless_gpu(W, H) as gpu:
        solid = two_spheres(gpu, "solid")
        wire = two_spheres(gpu, "wireframe")
        points = two_spheres(gpu, "points")
    half = W // 2
    assert abs(int(solid[:, :half].sum()) - int(solid[:, half:].sum())) < 30  # mirror images
    assert 100 < wire[:, :half].sum() < 0.7 * solid[:, :half].sum()  # the left one only
    assert (wire[:, half:] == solid[:, half:]).all()
    assert points[:, :half].sum() < 0.2 * wire[:, :half].sum()
    with pytest.raises(ValueError, match="fill must be one of"):
        from ecs_engine.render.assets.materials import Material

        Material("m", fill="dots")


def test_a_material_fill_without_the_device_feature_is_drawn_solid(monkeypatch, caplog):
    import logging

    with headless_gpu(W, H) as gpu:
        solid = two_spheres(gpu, "solid")
        monkeypatch.setitem(gpu.device.features, "fillModeNonSolid", False)
        with caplog.at_level(logging.WARNING, logger="ecs_engine"):
            fallback = two_spheres(gpu, "wireframe")
    assert (fallback == solid).all()
    assert len(caplog.records) == 1 and "fillModeNonSolid" in caplog.records[0].getMessage()
