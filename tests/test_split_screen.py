"""Several camera views drawn into one window (render/frame/views.py, view_graph.py): each
camera's picture lands in its Viewport's rectangle, in order, with its own matrices and layers;
a world of one camera draws exactly as before."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.components import Camera, DirectionalLight, Mesh, RenderLayers, Transform, Viewport
from ecs_engine.errors import UsageError
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.config import Form

W, H = 64, 32
RED, GREEN = -20.0, 20.0  # the cubes' x: far apart, so each camera sees only its own


def _world(mesh: int, split: bool = True, layers: bool = False) -> World:
    """A red cube and a green one; with `split` a camera over each in the window's left and right
    halves (with `layers`: both cameras at the same place, the red cube on layer 1 seen by the
    left one only, the green on layer 2 by the right one), else one camera on the red one."""
    world = World()
    red = materials(world).add(Material("red", "lambert", (1.0, 0.0, 0.0, 1.0)))
    green = materials(world).add(Material("green", "lambert", (0.0, 1.0, 0.0, 1.0)))
    for x, material, mask in ((RED, red, 0b10), (GREEN, green, 0b100)):
        x = 0.0 if layers else x
        extra = (RenderLayers(mask=mask),) if layers else ()
        place = Transform(position=(x, 0.0, 0.0), scale=(1.5, 1.5, 1.5))
        world.spawn(place, Mesh(handle=mesh, material=material), *extra)
    world.spawn(Transform(rotation=look_rotation((0.3, -0.5, -1.0))), DirectionalLight(illuminance=3.0))
    cams = [(RED, Viewport(width=0.5), 0b11), (GREEN, Viewport(x=0.5, width=0.5), 0b101)] if split else [(RED, None, 1)]
    for x, viewport, mask in cams:
        x = 0.0 if layers else x
        extra = [e for e in (viewport, RenderLayers(mask=mask) if layers else None) if e is not None]
        world.spawn(Transform(position=(x, 0.0, 4.0)), Camera(fov_y=math.radians(60.0)), *extra)
    return world


def _render(gpu, world: World, frames: int = 1, **settings) -> np.ndarray:
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
    try:
        default_schedule().run(world, 0.0)
        for _ in range(frames):
            renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].astype(np.int64)
    finally:
        renderer.destroy()


def _share(img: np.ndarray, channel: int) -> float:
    """The part of `img`'s pixels where `channel` clearly dominates."""
    px = img.reshape(-1, 3)
    others = np.delete(px, channel, axis=1).max(axis=1)
    return float(((px[:, channel] > 60) & (others < 30)).mean())


def _halves(img: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return img[:, : W // 2], img[:, W // 2 :]


@pytest.mark.parametrize("layers", [False, True])
def test_each_camera_draws_into_its_half(layers: bool) -> None:
    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        img = _render(gpu, _world(mesh, layers=layers), frames=3)
    left, right = _halves(img)
    assert _share(left, 0) > 0.1 and _share(left, 1) == 0.0  # the red cube, nothing green
    assert _share(right, 1) > 0.1 and _share(right, 0) == 0.0
    # each half is centred on its cube: its own camera's matrices, not the window's
    for half, channel in ((left, 0), (right, 1)):
        cols = np.flatnonzero((half[..., channel] > 60).any(axis=0))
        assert abs((cols.min() + cols.max()) / 2 - (W // 4 - 0.5)) <= 1.5


@pytest.mark.parametrize(
    "settings",
    [
        {"light_culling": "deferred"},
        {"mode": "indirect"},
        {"culling": "temporal"},
        {"mode": "per_entity"},
        {"msaa": 4},
        {"post": ("bloom", "ssao")},
        {"post": ("bloom",), "light_culling": "deferred"},
        {"post": ("fxaa",)},
        {"post": ("bloom", "fxaa"), "msaa": 4},
    ],
)
def test_split_screen_in_every_form_and_mode(settings: dict) -> None:
    """The deferred form (the G-buffer and lighting at the view's size), MSAA (the resolve into
    the view's corner), the GPU-driven path, temporal culling per camera, post effects (FXAA
    writing the view's rectangle)."""
    from ecs_engine.gpu.offscreen import OffscreenTarget

    samples = settings.pop("msaa", 1)
    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        if samples > 1:
            gpu.target.destroy()
            gpu.target = OffscreenTarget(gpu.device, W, H, samples=samples)
        left, right = _halves(_render(gpu, _world(mesh), frames=3, **settings))
    assert _share(left, 0) > 0.1 and _share(left, 1) == 0.0
    assert _share(right, 1) > 0.1 and _share(right, 0) == 0.0


def test_one_camera_draws_as_before_and_a_full_viewport_too() -> None:
    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        before = _render(gpu, _world(mesh, split=False))
        world = _world(mesh, split=False)
        (cam,) = world.query(Camera, write=()).entities()
        world.add(int(cam), Viewport())  # the whole window: the one camera's own path
        assert np.array_equal(_render(gpu, world), before)
        world.set(int(cam), Viewport(x=0.5, width=0.5))  # half the window: the rest cleared
        half = _render(gpu, world)
    assert _share(before, 0) > 0.05
    assert _share(half[:, W // 2 :], 0) > 0.1 and _share(half[:, : W // 2], 0) == 0.0
    assert len(np.unique(half[:, : W // 4].reshape(-1, 3), axis=0)) == 1  # the background alone


def test_a_split_window_back_to_one_camera_draws_as_before() -> None:
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        before = _render(gpu, _world(mesh, split=False))
        world = _world(mesh)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            assert renderer.target.form == Form.HDR and renderer.views.on
            right = [int(e) for e in world.query(Camera, write=()).entities()][1]
            world.destroy(right)
            left = int(world.query(Camera, write=()).entities()[0])
            world.remove(left, Viewport)
            renderer.ensure_output()
            renderer.render(world, readback=True)
            assert not renderer.views.on and renderer.target.form == Form.DIRECT
            assert renderer.views.graphs == [] and renderer.views.extractors == {}  # nothing kept
            assert np.array_equal(gpu.target.pixels()[..., :3].astype(np.int64), before)
        finally:
            renderer.destroy()


def test_occlusion_culling_and_post_effects_are_refused_with_several_views() -> None:
    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        with pytest.raises(UsageError, match="occlusion culling with several camera views"):
            _render(gpu, _world(mesh), mode="indirect", culling="occlusion")
        from ecs_engine.app.scenes import default_schedule
        from ecs_engine.render.frame.renderer import Renderer

        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, tone_map="aces")
        try:
            world = _world(mesh)
            default_schedule().run(world, 0.0)
            renderer.output.set_post([lambda cb, inputs: None], [])  # a callable effect (a test's spy)
            with pytest.raises(UsageError, match="a post effect given as a callable with several camera views"):
                renderer.render(world)
        finally:
            renderer.destroy()


def test_each_view_replays_its_own_slot_and_never_another_view_s() -> None:
    """Two views, two frame slots: each view keeps its slot, a still frame is submitted again;
    a moved camera's half follows it, the other half stays."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        world = _world(mesh)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            schedule = default_schedule()
            schedule.run(world, 0.0)
            for _ in range(4):
                renderer.render(world, readback=False)
            assert renderer.replay.replayed >= 2
            renderer.render(world, readback=True)
            still = gpu.target.pixels()[..., :3].astype(np.int64)
            right = int(world.query(Camera, write=()).entities()[1])
            world.set(right, Transform(position=(GREEN + 1.0, 0.0, 4.0)))  # the green cube moves left in its half
            schedule.run(world, 0.0)
            renderer.render(world, readback=True)
            moved = gpu.target.pixels()[..., :3].astype(np.int64)
        finally:
            renderer.destroy()
    assert np.array_equal(_halves(moved)[0], _halves(still)[0])
    assert not np.array_equal(_halves(moved)[1], _halves(still)[1])
    cols = np.flatnonzero((_halves(moved)[1][..., 1] > 60).any(axis=0))
    assert (cols.min() + cols.max()) / 2 < W // 4 - 2


def test_print_graph_shows_each_view_s_graph_in_order() -> None:
    import subprocess
    import sys

    args = ["split_screen", "--print-graph", "--validate", "--width", "64", "--height", "48"]
    proc = subprocess.run(
        [sys.executable, "-m", "ecs_engine", "demo", *args], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0 and proc.stderr == "", proc.stdout + proc.stderr
    text = proc.stdout
    heads = [line for line in text.splitlines() if line.startswith("view ")]
    assert [h.split(":")[0] for h in heads] == ["view 1 of 3", "view 2 of 3", "view 3 of 3"]
    assert heads[0].endswith("into the window at (0, 0, 32, 48)") and "frame graph 32x48" in text
    assert text.count("clear_target") == 1 and text.count("readback (side effect)") == 1
    assert text.count("writes target region COLOR_WRITE") == 3


def test_views_coming_and_going_between_frames() -> None:
    """An inset added over the right half, then taken away: the view before it becomes the last
    (the target's final layout, the readback) and the picture is the two halves' again."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        world = _world(mesh)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        schedule = default_schedule()
        try:

            def frame() -> np.ndarray:
                schedule.run(world, 0.0)
                renderer.render(world, readback=True)
                return gpu.target.pixels()[..., :3].astype(np.int64)

            two = frame()
            inset = world.spawn(  # the red cube, in the right half's top right corner
                Transform(position=(RED, 0.0, 4.0)),
                Camera(fov_y=math.radians(60.0)),
                Viewport(x=0.75, width=0.25, height=0.5, order=1),
            )
            three = frame()
            world.destroy(inset)
            again = frame()
        finally:
            renderer.destroy()
    corner = (slice(0, H // 2), slice(3 * W // 4, W))
    assert _share(three[corner], 0) > 0.05 and _share(two[corner], 0) == 0.0
    assert np.array_equal(again, two)


@pytest.mark.parametrize("transparency", ["sorted", "weighted"])
def test_blended_rows_in_each_view(transparency: str) -> None:
    """Half-transparent cubes in both halves, forward over each view's scene (sorted) or
    accumulated at the view's size in the deferred form (weighted)."""
    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        world = _world(mesh)
        library = materials(world)
        for x, color in ((RED, (1.0, 0.0, 0.0, 0.5)), (GREEN, (0.0, 1.0, 0.0, 0.5))):
            glass = library.add(Material(f"glass{x}", "lambert", color, alpha_mode="blend"))
            world.spawn(Transform(position=(x, 0.0, 0.0), scale=(1.5, 1.5, 1.5)), Mesh(handle=mesh, material=glass))
        for eid in [int(e) for e in world.query(Mesh, write=()).entities()][:2]:
            world.destroy(eid)  # the opaque cubes go: the blended ones alone
        settings = {"transparency": transparency, "light_culling": "deferred" if transparency == "weighted" else "auto"}
        left, right = _halves(_render(gpu, world, frames=2, **settings))

    def tinted(half: np.ndarray, channel: int) -> np.ndarray:  # the glass over the background
        return half[..., channel] > np.delete(half, channel, axis=-1).max(axis=-1) + 40

    assert tinted(left, 0).mean() > 0.05 and not tinted(left, 1).any()
    assert tinted(right, 1).mean() > 0.05 and not tinted(right, 0).any()
    for half, channel in ((left, 0), (right, 1)):  # each centred in its half (its view's size)
        cols = np.flatnonzero(tinted(half, channel).any(axis=0))
        assert abs((cols.min() + cols.max()) / 2 - (W // 4 - 0.5)) <= 1.5


def test_deferred_views_keep_their_own_lighting_sets_and_replay() -> None:
    """Each view's G-buffer is its graph's: one deferred lighting set per view, named once
    (re-naming one waits for the device), so a still split screen replays its frames."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        world = _world(mesh)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, light_culling="deferred")
        try:
            default_schedule().run(world, 0.0)
            for _ in range(6):
                renderer.render(world)
            assert len(renderer.views.lighting) == 2
            assert all(lighting._named is not None for lighting in renderer.views.lighting.values())
            assert renderer.replay.replayed >= 6
        finally:
            renderer.destroy()


@pytest.mark.parametrize("settings", [{"post": ("bloom", "ssao", "fxaa")}, {"light_culling": "deferred"}])
def test_a_still_split_screen_waits_for_nothing_and_replays(settings: dict) -> None:
    """Per view what keeps sets for one graph's images (the deferred lighting, the effects'
    pipelines): once made, no frame waits for the device or writes a set, and frames replay."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        world = _world(mesh)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
        waits = []
        real = gpu.device.wait_idle
        try:
            default_schedule().run(world, 0.0)
            for _ in range(4):
                renderer.render(world)
            gpu.device.wait_idle = lambda: (waits.append(1), real())[1]
            version, replayed = gpu.device.objects_version, renderer.replay.replayed
            for _ in range(4):
                renderer.render(world)
            assert waits == [] and gpu.device.objects_version == version
            assert renderer.replay.replayed - replayed == 8  # 4 frames of 2 views
        finally:
            gpu.device.wait_idle = real
            renderer.destroy()
