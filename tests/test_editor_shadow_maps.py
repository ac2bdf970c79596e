"""The editor's view of each shadow map (issue 15): a casting light's section shows its layers
(a sun's cascades, a spot light's map, a point light's six cube faces) as grey thumbnails drawn
from the shadow maps themselves (near white, far black), follows the maps when they are made
anew, and shows nothing for a light without a Shadow; validation stays clean throughout."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("imgui_bundle")

from test_editor import Scene

from ecs_engine.app.loop import apply_requests
from ecs_engine.app.settings import RunOptions
from ecs_engine.components import DirectionalLight, PointLight, Shadow, SpotLight

W, H = 1024, 768  # room for the inspector's whole light section, thumbnails included


class ShadowsEditor(Scene):
    """test_editor's headless editor on the shadows scene, larger, the inspector pinned to the
    right half at full height and in front, so that the thumbnails are on screen."""

    def __init__(self) -> None:
        from imgui_bundle import imgui

        from ecs_engine.app.editor_session import EditorSession
        from ecs_engine.app.offscreen import OffscreenSource
        from ecs_engine.app.perf import PerfMonitor
        from ecs_engine.app.session import Session

        self.imgui = imgui
        self.source = OffscreenSource()
        self.state = Session(RunOptions(scene="shadows", width=W, height=H, threads=2, validate=True), self.source)
        self.gpu = self.state.gpu
        self.session = EditorSession(self.state, ("shadows",), 4, max_ui_hz=None)
        self.perf = PerfMonitor()
        self.stats = None
        self.io = imgui.get_io()
        self.editor = self.session.editor
        self.overlay = self.session.renderer
        self.world = self.state.world
        draw = self.editor.draw

        def pinned(world, stats):
            draw(world, stats)
            imgui.set_window_pos("Inspector", (W - 440, 0))
            imgui.set_window_size("Inspector", (440, H))
            imgui.set_window_focus("Inspector")

        self.editor.draw = pinned

    def frame(self, mouse=None, down=None) -> None:
        s = self.state
        s.schedule.run(s.world, 1 / 60)
        self.session.build(s.world, self.stats, self.perf, 1 / 60, W, H)
        self.stats = s.renderer.render(s.world, readback=True)
        apply_requests(s, self.session)

    def select(self, eid: int, frames: int = 2) -> None:
        self.editor.selected = eid
        for _ in range(frames):  # the first builds the section, the next shows what it registered
            self.frame()

    def light(self, kind: type) -> int:
        return int(self.world.query(kind, write=()).entities()[0])

    def image_commands(self) -> list[int]:
        """The texture ids of the last UI's commands that draw a registered (user) image (not
        the Scene window's: the viewport's image, app/editor_viewport.py)."""
        data = self.imgui.get_draw_data()
        ids = [int(cmd.get_tex_id()) for dl in data.cmd_lists for cmd in dl.cmd_buffer if cmd.elem_count]
        scene = self.session.viewport._tex_id
        return [i for i in ids if i in self.overlay.images and i != scene]

    def thumbnails_drawn(self) -> int:
        """Registered images the overlay drew, less the Scene window's (the viewport's image)."""
        return self.overlay.counts.images - (self.session.viewport.size is not None)

    def thumbnails(self) -> dict[int, np.ndarray]:
        """Layer -> the screenshot's pixels (RGB) inside its thumbnail (a pixel's margin left out)."""
        pixels = self.gpu.target.pixels()[..., :3]
        out = {}
        for layer, (x0, y0, x1, y1) in self.editor.shadow_maps.rects.items():
            assert 0 <= x0 and x1 <= W and 0 <= y0 and y1 <= H, "the thumbnail is off screen"
            out[layer] = pixels[int(y0) + 1 : int(y1) - 1, int(x0) + 1 : int(x1) - 1].astype(int)
        return out


@pytest.fixture
def scene(monkeypatch):
    from ecs_engine.app import editor_dock

    monkeypatch.setattr(editor_dock, "WIDE", 0.0)  # the inspector down the whole right side
    s = ShadowsEditor()
    try:
        yield s
    finally:
        s.close()


def light_layers(scene: ShadowsEditor, eid: int) -> list[int]:
    return [v.layer for v in scene.state.renderer.shadows.last_views if v.entity == eid]


def test_each_casting_light_shows_its_shadow_map_layers(scene, tmp_path):
    from PIL import Image

    scene.frame()
    for kind, count in ((DirectionalLight, 4), (SpotLight, 1), (PointLight, 6)):
        eid = scene.light(kind)
        scene.select(eid)
        drawn = scene.editor.shadow_maps.drawn
        assert sorted(drawn) == light_layers(scene, eid) and len(drawn) == count
        # ImGui's commands name the registered ids, one command a layer, and the overlay draws them
        assert sorted(scene.image_commands()) == sorted(drawn.values())
        assert scene.thumbnails_drawn() == count
        if kind is DirectionalLight:
            Image.fromarray(scene.gpu.target.pixels()[..., :3]).save(tmp_path / "sun_shadow_maps.png")
            sun = scene.thumbnails()
    # grey: the depth in R, G and B
    for pixels in sun.values():
        assert np.abs(pixels[..., 0] - pixels[..., 1]).max() <= 2 and np.abs(pixels[..., 1] - pixels[..., 2]).max() <= 2
    # the sun shines straight down on the ground and the cube: a cascade that holds the cube shows
    # its top nearer the light than the ground around it (reverse-Z: brighter), not one grey
    grey = [p[..., 0] for p in sun.values()]
    assert any(g.max() - g.min() > 30 for g in grey)
    assert any(np.median(g) < g.max() - 30 and (g > np.median(g) + 30).mean() < 0.5 for g in grey)


def test_new_maps_are_registered_again_and_the_old_ids_dropped(scene):
    world = scene.world
    sun = scene.light(DirectionalLight)
    for kind, texels in ((DirectionalLight, 256), (SpotLight, 256), (PointLight, 128)):
        world.set(scene.light(kind), Shadow, resolution=texels)
    scene.frame()
    scene.select(sun)
    shadows = scene.state.renderer.shadows
    maps, old = shadows.maps, dict(scene.editor.shadow_maps.drawn)
    assert maps.resolution == 256 and len(old) == 4 and scene.thumbnails_drawn() == 4
    # the UI is no longer rebuilt (the rate limit): the last one's draws name the old maps' ids
    scene.session.min_interval_s = 1e9
    scene.editor.set(world, sun, Shadow, resolution=512)
    scene.frame()  # the maps are made anew in this frame's render: the overlay drops their ids
    assert shadows.maps is not maps and maps.destroyed and shadows.maps.resolution == 512
    assert not any(tex_id in scene.overlay.images for tex_id in old.values())
    assert scene.thumbnails_drawn() == 0
    scene.frame()
    scene.session.min_interval_s = 0.0
    scene.frame()  # built again: the new maps' layers registered under new ids
    new = scene.editor.shadow_maps.drawn
    assert sorted(new) == sorted(old) and not set(new.values()) & set(old.values())
    assert scene.thumbnails_drawn() == 4 and sorted(scene.image_commands()) == sorted(new.values())
    grey = [p[..., 0] for p in scene.thumbnails().values()]
    assert any(g.max() - g.min() > 30 for g in grey)
    for _ in range(4):  # the dropped ids' sets go back to the pool once no frame in flight reads them
        scene.frame()
    assert scene.overlay.images._retired == []


def test_a_light_without_a_shadow_shows_no_thumbnails(scene):
    world = scene.world
    scene.frame()
    spot = scene.light(SpotLight)
    scene.select(spot)
    assert scene.thumbnails_drawn() == 1
    world.remove(spot, Shadow)  # what the "casts shadows" checkbox does
    scene.frame()
    scene.frame()
    assert scene.editor.shadow_maps.drawn == {} and scene.thumbnails_drawn() == 0
    assert scene.image_commands() == []
    assert spot not in {v.entity for v in scene.state.renderer.shadows.last_views}
    # the sun still casts: selecting it shows its cascades
    scene.select(scene.light(DirectionalLight))
    assert scene.thumbnails_drawn() == 4
