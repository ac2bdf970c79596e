"""Render to texture (render/frame/texture_views.py): the monitor demo's screen shows what its
second camera sees (a magenta cube only that camera's layers hold), follows that camera when it
moves, and is black without it."""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.components import Camera, RenderTexture, Transform

W, H = 80, 60


class Room:
    """The monitor demo's world on a headless target; `frame` runs the schedule and draws it
    with the room's Renderer (made on the first frame, destroyed with the fixture)."""

    def __init__(self, gpu: Any, world: World, schedule: Any) -> None:
        self.gpu, self.world, self.schedule = gpu, world, schedule
        self.renderer: Any = None

    def frame(self, readback: bool = True) -> np.ndarray:
        from ecs_engine.render.frame.renderer import Renderer

        self.schedule.run(self.world, 0.0)
        if self.renderer is None:
            self.renderer = Renderer(self.gpu.device, self.gpu.target, self.gpu.meshes)
        self.renderer.render(self.world, readback=readback)
        return self.gpu.target.pixels()[..., :3].astype(np.int64) if readback else np.empty(0)

    def new_renderer(self) -> None:
        """The next frame is drawn by a new Renderer."""
        if self.renderer is not None:
            self.renderer.destroy()
            self.renderer = None


@pytest.fixture
def room() -> Iterator[Room]:
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.demos import monitor

    with headless_gpu(W, H) as gpu:
        world = World()
        monitor.build(world, gpu.meshes.add)
        made = Room(gpu, world, default_schedule())
        try:
            yield made
        finally:
            made.new_renderer()


def _magenta(img: np.ndarray) -> np.ndarray:
    """Where the picture is clearly magenta (red and blue far above green)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 90) & (b > 80) & (g < 0.5 * np.minimum(r, b))


def _monitor_camera(world: World) -> int:
    return int(world.query(Camera, RenderTexture, write=()).entities()[0])


def test_the_screen_shows_the_second_camera_s_picture_and_follows_it(room: Room) -> None:
    world = room.world
    shown = room.frame()
    cam = _monitor_camera(world)
    place = world.get(cam, Transform)
    world.set(cam, Transform(position=np.asarray(place.position) + (1.2, 0.0, 0.0), rotation=place.rotation))
    moved = room.frame()
    world.remove(cam, RenderTexture)  # no camera draws it: the screen stays black
    world.remove(cam, Camera)
    room.schedule.run(world, 0.0)
    room.new_renderer()
    dark = room.frame()
    seen, after = _magenta(shown), _magenta(moved)
    assert seen.sum() >= 20  # the cube on the screen, in the room's picture
    assert not _magenta(dark).any()  # the room's camera never sees the cube itself
    # the second camera moved right: its cube moved left in its picture, and on the screen
    cols = np.flatnonzero(seen.any(axis=0)), np.flatnonzero(after.any(axis=0))
    assert after.sum() >= 20 and cols[1].mean() < cols[0].mean() - 1.0
    # only the screen changed (and what its light falls on: nothing), the room stayed
    changed = np.abs(moved - shown).max(axis=-1) > 8
    rows, columns = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
    assert changed.sum() and np.ptp(rows) < H // 2 and np.ptp(columns) < W // 2


@pytest.mark.parametrize("settings", [{"light_culling": "deferred"}, {"tone_map": "aces"}, {"msaa": 4}])
def test_the_screen_shows_it_in_every_form(room: Room, settings: dict) -> None:
    """The texture view draws in the window's form (direct above; hdr, deferred, MSAA here)."""
    from ecs_engine.gpu.offscreen import OffscreenTarget

    samples = settings.pop("msaa", 1)
    gpu = room.gpu
    if samples > 1:
        gpu.target.destroy()
        gpu.target = OffscreenTarget(gpu.device, W, H, samples=samples)
    shown = render_world(gpu, room.world, **settings)
    assert _magenta(shown).sum() >= 20


def test_a_texture_view_and_a_split_window_in_one_frame(room: Room) -> None:
    """The texture view first, then the window's view in its part of the window (the hdr form)."""
    from ecs_engine.components import FlyCamera, Viewport

    (view,) = room.world.query(Camera, FlyCamera, write=()).entities()
    room.world.add(int(view), Viewport(x=0.25, width=0.5))
    shown = render_world(room.gpu, room.world)
    seen = _magenta(shown)
    assert seen.sum() >= 5 and not seen[:, : W // 4].any() and not seen[:, 3 * W // 4 :].any()
    assert len(np.unique(shown[:, : W // 4 - 1].reshape(-1, 3), axis=0)) == 1  # outside the view: background


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
@pytest.mark.parametrize("scene", ["monitor", "split_screen"])
def test_the_views_in_a_window(scene: str, tmp_path) -> None:
    """On a swapchain: the first view's submit waits for the image, the last one's signals the
    present (render/frame/views.py); the screenshot reads the last frame back."""
    from PIL import Image

    from ecs_engine.app.settings import RunOptions
    from ecs_engine.app.window import open_glfw, run_windowed

    shot = tmp_path / "shot.png"
    options = RunOptions(scene=scene, width=W, height=H, frames=6, screenshot=str(shot), validate=True, quiet=True)
    glfw = open_glfw()
    assert glfw is not None
    result = run_windowed(options, glfw)
    assert result.validation_messages == [] and result.frames == 6
    pixels = np.asarray(Image.open(shot).convert("RGB")).astype(np.int64)
    if scene == "monitor":
        assert _magenta(pixels).sum() >= 10
    else:  # three views drawn: no pixel left undrawn (black)
        assert (pixels.sum(axis=-1) > 0).all()


def test_a_texture_view_that_goes_away_leaves_nothing_behind(room: Room) -> None:
    """Its camera removed: the next frame draws the window alone and what the view kept (its
    target, graphs, lighting) is destroyed; the screen keeps the last picture it was given."""
    room.frame(readback=False)
    assert set(room.renderer.views.targets) == {"monitor"} and room.renderer.views.on
    room.world.destroy(_monitor_camera(room.world))
    shown = room.frame()
    views = room.renderer.views
    assert views.targets == {} and views.texture_graphs == {} and not views.on
    assert _magenta(shown).sum() >= 20


def test_a_saved_monitor_world_loads_with_its_render_target(tmp_path) -> None:
    """A scene file keeps a render target as one (its name and size, not its black texel): the
    loaded world's screen shows the second camera's picture again; a render target of that name
    in the world loaded into is reused, and one of another size there is refused."""
    import json
    import zipfile

    from ecs_engine.demos import monitor
    from ecs_engine.ecs.scene_file import SceneFileError, load_world, save_world
    from ecs_engine.render.assets.materials import materials
    from ecs_engine.render.assets.scene_assets import scene_codecs

    path = tmp_path / "monitor.scene"
    with headless_gpu(W, H) as gpu:
        world = World()
        monitor.build(world, gpu.meshes.add)
        save_world(world, path, resources=scene_codecs(gpu.meshes))
        loaded = World()
        load_world(path, loaded, resources=scene_codecs(gpu.meshes))
        shown = render_world(gpu, loaded)
        twice = World()  # loaded again into a world that has the render target: one, reused
        load_world(path, twice, resources=scene_codecs(gpu.meshes))
        load_world(path, twice, resources=scene_codecs(gpu.meshes))
        other = World()
        materials(other).textures.render_target("monitor", 64, 64)
        with pytest.raises(SceneFileError, match=r"'monitor' is 64 x 64 pixels here and 128 x 96 in the file"):
            load_world(path, other, resources=scene_codecs(gpu.meshes))
    with zipfile.ZipFile(path) as archive:
        header = json.loads(archive.read("header.json"))
    (saved,) = [r for r in header["resources"] if r["name"] == "materials"]
    assert saved["doc"]["textures"] == [{"name": "monitor", "render_target": [128, 96]}] and not saved["arrays"]
    textures = materials(loaded).textures
    target = textures.render_target_of(textures.render_target_handle("monitor"))
    assert target is not None and (target.width, target.height) == monitor.SCREEN
    assert [t.name for t in materials(twice).textures.render_targets] == ["monitor"]
    assert _magenta(shown).sum() >= 20
