"""Bloom and SSAO in a view smaller than the window's images (a split-screen camera view, the
editor's viewport): each view draws into the corner of the window's shared HDR and depth images,
and the effects work on that rectangle as if it were the whole image. So a view's picture is
the one a window of the view's size gives (same camera, same scene), and nothing outside the
rectangle (another view's pixels, an earlier frame's) reaches it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world
from image_readback import target_corner

from ecs_engine import World
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform, Viewport
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh

W, H = 64, 32
RED, WHITE = -20.0, 100.0  # the red cube's x (the left view's), the bright one's (no view's)
TOLERANCE = 2  # sRGB levels: the same arithmetic, up to the order of floating-point sums
POSTS = [("bloom",), ("ssao",), ("bloom", "ssao")]


def _world(mesh: int) -> World:
    """A red cube on a grey floor (SSAO's creases) lit hard (HDR values above 1: bloom), a
    bright emissive slab far off at x = WHITE, and one camera looking at the red cube."""
    world = World()
    table = materials(world)
    red = table.add(Material("red", "lambert", (1.0, 0.0, 0.0, 1.0)))
    grey = table.add(Material("grey", "lambert", (0.5, 0.5, 0.5, 1.0)))
    white = table.add(Material("white", "lambert", (1.0, 1.0, 1.0, 1.0), emissive=(40.0, 40.0, 40.0)))
    world.spawn(Transform(position=(RED, 0.0, 0.0), scale=(1.5, 1.5, 1.5)), Mesh(handle=mesh, material=red))
    floor = Transform(position=(0.0, -0.8, 0.0), scale=(300.0, 0.1, 20.0))
    world.spawn(floor, Mesh(handle=mesh, material=grey))
    world.spawn(Transform(position=(WHITE, 0.0, 0.0), scale=(20.0, 20.0, 1.0)), Mesh(handle=mesh, material=white))
    world.spawn(Transform(rotation=look_rotation((0.3, -0.5, -1.0))), DirectionalLight(illuminance=2.0))
    world.spawn(Transform(position=(RED, 0.3, 4.0)), Camera(fov_y=math.radians(60.0)))
    return world


def _camera(world: World) -> int:
    return int(world.query(Camera, write=()).entities()[0])


def _reference(post: tuple[str, ...], size: tuple[int, int]) -> np.ndarray:
    """The red cube's camera alone in a window of `size`."""
    with headless_gpu(*size) as gpu:
        return render_world(gpu, _world(gpu.meshes.add(cube_mesh())), frames=2, post=post)


def _split_after_bright(gpu, post: tuple[str, ...]) -> np.ndarray:
    """One Renderer: a frame of the camera on the bright slab over the whole window (its HDR
    image is bright everywhere), then the window split: the camera on the red cube in the left
    half, a second one on the slab's far side in the right half. The window's pixels."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    world = _world(gpu.meshes.add(cube_mesh()))
    camera = _camera(world)
    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, post=post)
    try:
        schedule = default_schedule()
        world.set(camera, Transform(position=(WHITE, 5.0, 3.0)))
        schedule.run(world, 0.0)
        renderer.render(world, readback=True)
        bright = gpu.target.pixels()[..., :3].astype(np.int64)
        assert bright.min() > 200  # the slab fills the window
        world.set(camera, Transform(position=(RED, 0.3, 4.0)))
        world.add(camera, Viewport(width=0.5))
        behind = Transform(position=(WHITE, 5.0, -3.0), rotation=look_rotation((0.0, 0.0, 1.0)))
        world.spawn(behind, Camera(fov_y=math.radians(60.0)), Viewport(x=0.5, width=0.5))
        schedule.run(world, 0.0)
        renderer.ensure_output()
        for _ in range(2):
            renderer.render(world, readback=True)
        assert renderer.views.on
        return gpu.target.pixels()[..., :3].astype(np.int64)
    finally:
        renderer.destroy()


@pytest.mark.parametrize("post", POSTS)
def test_a_split_view_s_effects_see_only_its_own_rectangle(post: tuple[str, ...]) -> None:
    """The left view equals a window of its size, though the window's HDR image held the bright
    slab everywhere a frame before and the right view shows it (bright) this frame."""
    with headless_gpu(W, H) as gpu:
        window = _split_after_bright(gpu, post)
    left, right = window[:, : W // 2], window[:, W // 2 :]
    assert right.min() > 200  # the right view sees the slab, the left one must not show it
    expected = _reference(post, (W // 2, H))
    assert np.abs(left - expected).max() <= TOLERANCE


@pytest.mark.parametrize("post", [("bloom",), ("ssao",)])
def test_the_effects_change_the_reference_picture(post: tuple[str, ...]) -> None:
    """The comparisons above see each effect: it moves the view's pixels by more than the
    tolerance (bloom spreads the lit cube's light, SSAO darkens the crease on the floor)."""
    size = (W // 2, H)
    assert np.abs(_reference(post, size) - _reference((), size)).max() > 4 * TOLERANCE


class _NoUi:
    """An overlay that draws nothing: the renderer draws the editor's viewport only with a UI."""

    def rebuild(self, target) -> None:
        pass

    def prepare(self, slot: int, slots: int) -> None:
        pass

    def record(self, cb, slot: int, width: int, height: int) -> None:
        pass


@pytest.mark.parametrize("post", POSTS)
def test_the_editor_viewport_s_effects_see_only_its_rectangle(post: tuple[str, ...]) -> None:
    """A viewport smaller than the window (drawn into the corner of the window's HDR and depth
    images, which a whole-window frame left bright) gives a window of its size's picture."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer
    from ecs_engine.render.frame.viewport import EditorViewport

    size = (W // 2, H)
    with headless_gpu(W, H) as gpu:
        world = _world(gpu.meshes.add(cube_mesh()))
        camera = _camera(world)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, post=post)
        viewport = renderer.viewport = EditorViewport(gpu.device)
        renderer.overlay = _NoUi()
        try:
            schedule = default_schedule()
            world.set(camera, Transform(position=(WHITE, 5.0, 3.0)))  # the slab over the whole window
            schedule.run(world, 0.0)
            renderer.render(world, readback=True)
            assert gpu.target.pixels()[..., :3].min() > 200
            world.set(camera, Transform(position=(RED, 0.3, 4.0)))
            viewport.size = size
            schedule.run(world, 0.0)
            for _ in range(2):
                renderer.render(world, readback=True)
            target = viewport.target
            assert target is not None and (target.width, target.height) == (W, H)
            picture = target_corner(gpu.target, target.color, size, target.final_layout)  # the window's copy
        finally:
            renderer.destroy()
    expected = _reference(post, size)
    assert np.abs(picture - expected).max() <= TOLERANCE
