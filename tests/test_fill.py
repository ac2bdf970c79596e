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
from ecs_engine.render.primitives import sphere_mesh

W, H = 96, 96


def covered(gpu, fill: str) -> int:
    """Pixels not the clear colour, drawing a sphere with `fill`."""
    from ecs_engine.render.renderer import Renderer

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
    from ecs_engine.render.renderer import Renderer

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
