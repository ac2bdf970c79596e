"""The ImGui editor and Perf window on the engine's Vulkan renderer (lavapipe, validation on):
the overlay is drawn, synthetic input edits a component, settings requests rebuild what they
need, the entity browser stays cheap for large worlds, the texture protocol runs its course."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

pytest.importorskip("imgui_bundle")

from ecs_engine.app.loop import apply_requests, run
from ecs_engine.app.settings import RunOptions
from ecs_engine.components import Camera, Mesh, PointLight, Transform
from ecs_engine.jobs import JobPool
from ecs_engine.maths.camera import yaw_pitch_quat, yaw_pitch_roll, yaw_pitch_roll_quat

W, H = 1024, 720


def headless(tmp_path, editor: bool, size=(W, H), **kw):
    result = run(
        RunOptions(
            scene="grid100",
            width=size[0],
            height=size[1],
            frames=kw.pop("frames", 6),
            validate=True,
            quiet=True,
            editor=editor,
            screenshot=str(tmp_path / f"e{editor}.png"),
            **kw,
        )
    )
    assert result.validation_messages == []
    return result


def test_the_overlay_is_drawn_over_the_scene(tmp_path):
    size = (1280, 720)  # room for the scene between the windows
    plain = headless(tmp_path, editor=False, size=size)
    ui = headless(tmp_path, editor=True, size=size, perf_json=str(tmp_path / "perf.json"))
    diff = np.abs(ui.pixels[..., :3].astype(int) - plain.pixels[..., :3]).max(axis=2) > 24
    # docked panels: settings down the left, the inspector down the right, the entity list and
    # Perf under the scene cover it there (text, frames and widgets: the windows' dark
    # background is close to the clear colour)...
    assert diff[20:300, 20:280].mean() > 0.05 and diff[20:100, 990:1260].mean() > 0.02
    assert diff[520:700, 310:600].mean() > 0.02 and diff[520:700, 620:950].mean() > 0.02
    assert ui.editor.renderer.counts.commands > 3
    # ...and the Scene window shows the scene as a window of its own size would: the same
    # pixels (its image drawn 1:1), not the full window's picture cut
    x0, y0, x1, y1 = (round(v) for v in ui.editor.editor.scene.rect)
    alone = headless(tmp_path, editor=False, size=(x1 - x0, y1 - y0))
    node = ui.pixels[y0:y1, x0:x1, :3].astype(int)
    assert (np.abs(node - alone.pixels[..., :3]).max(axis=2) <= 1).mean() >= 0.999
    assert (np.abs(node - plain.pixels[y0:y1, x0:x1, :3]).max(axis=2) > 24).mean() > 0.05  # not the full window's
    doc = json.loads((tmp_path / "perf.json").read_text())
    assert len(doc["frames"]) == 6 and doc["meta"]["editor"] is True


def test_gpu_ms_is_positive_and_fps_is_the_wall_clock_rate(tmp_path):
    result = headless(tmp_path, editor=True, frames=10)
    perf = result.perf
    gpu = perf.series("gpu_ms")
    assert np.nanmin(gpu) > 0
    ends = np.array(result.frame_end)
    warm = perf.warmup_frames  # pipelines and JIT: left out of the Perf window's figures
    wall_fps = (len(ends) - warm) / (ends[-1] - ends[warm - 1])
    assert perf.fps == pytest.approx(wall_fps, rel=0.05)
    np.testing.assert_array_equal(perf.series("cpu_ms"), result.cpu_ms[warm:])


class Scene:
    """The editor on a headless session, driven frame by frame."""

    def __init__(self, scene: str = "grid100", size: tuple[int, int] = (W, H)) -> None:
        from ecs_engine.app.editor_session import EditorSession
        from ecs_engine.app.offscreen import OffscreenSource
        from ecs_engine.app.perf import PerfMonitor
        from ecs_engine.app.session import Session

        self.source = OffscreenSource()
        self.size = size
        options = RunOptions(scene=scene, width=size[0], height=size[1], threads=2, validate=True)
        self.state = Session(options, self.source)
        self.gpu = self.state.gpu
        # every frame builds the UI (the default rate limit would drop clicks on a fast machine)
        scenes = tuple(dict.fromkeys((scene, "cube", "grid100", "model")))  # as the CLI: the opened one first
        self.session = EditorSession(self.state, scenes, 4, max_ui_hz=None)
        self.perf = PerfMonitor()
        self.stats = None
        from imgui_bundle import imgui

        self.io = imgui.get_io()

    def frame(self, mouse=None, down=None) -> None:
        if mouse is not None:
            self.io.add_mouse_pos_event(*mouse)
        if down is not None:
            self.io.add_mouse_button_event(0, down)
        s = self.state
        s.schedule.run(s.world, 1 / 60)
        self.session.build(s.world, self.stats, self.perf, 1 / 60, *self.size)
        self.stats = s.renderer.render(s.world, readback=True)
        self.perf.frame(1.0, self.stats.record_ms, self.stats.gpu_ms, draws=self.stats.draws)
        apply_requests(s, self.session)  # as the run loop does

    def close(self) -> None:
        self.session.destroy()
        self.state.close()
        assert self.source.validation_messages() == []


def centre(rect):
    return ((rect[0] + rect[2]) / 2, (rect[1] + rect[3]) / 2)


def test_synthetic_input_selects_an_entity_and_drags_its_position(scene):
    editor = scene.session.editor
    for _ in range(3):
        scene.frame()
    first = int(editor.filtered_ids(scene.state.world)[0])
    row = centre(editor.rects["first row"])
    scene.frame(mouse=row)
    scene.frame(down=True)
    scene.frame(down=False)
    assert editor.selected == first
    before = scene.state.world.get(first, Transform).position.copy()
    scene.frame()  # the inspector appears
    x0, y0, x1, y1 = editor.rects["position"]
    start = (x0 + (x1 - x0) / 6, (y0 + y1) / 2)  # the x field: the first of three
    scene.frame(mouse=start)
    scene.frame(down=True)
    for dx in (10, 20, 30, 40):
        scene.frame(mouse=(start[0] + dx, start[1]))
    scene.frame(down=False)
    after = scene.state.world.get(first, Transform).position
    assert after[0] > before[0] + 0.5  # dragged right: 0.05 per pixel
    assert after[1:] == pytest.approx(before[1:])
    assert scene.session.renderer.counts.commands > 5


def test_settings_requests_rebuild_what_they_need(scene):
    scene.frame()
    editor = scene.session.editor
    renderer, path = scene.state.renderer, scene.state.renderer.path
    editor.requested.mode, editor.requested.threads, editor.requested.culling = "indirect", 3, "none"
    scene.frame()  # the request is applied after this frame
    # the path is swapped; the renderer, its frame slots and buffers stay
    assert scene.state.renderer is renderer and renderer.path is not path and renderer.mode == "indirect"
    assert scene.state.pool.threads == 3 and scene.state.renderer.culling == "none"
    assert scene.state.world.resources[JobPool] is scene.state.pool  # one pool, resized in place
    scene.frame()
    assert scene.stats.instances == 100 and scene.gpu.target.pixels()[..., :3].max() > 30
    editor.selected = int(scene.state.world.entities()[5])
    editor.requested.scene = "cube"
    scene.frame()
    world = scene.state.world
    assert world.query(Mesh, write=()).count() == 1 and scene.state.settings.scene == "cube"
    assert editor.selected is None  # ids of the old world name other entities in the new one
    scene.frame()
    assert scene.stats.instances == 1  # the indirect path counts the new scene's mesh


def test_a_request_the_session_refuses_changes_nothing_and_says_why(scene, monkeypatch):
    scene.frame()
    scene.frame()  # the first frame is drawn before the dock layout gives the scene its node
    drawn = scene.stats.instances
    editor = scene.session.editor
    monkeypatch.setitem(scene.state.device.features, "drawIndirectCount", False)  # a device without it
    editor.requested.mode, editor.requested.threads = "indirect", 3
    scene.frame()
    assert "lacks drawIndirectCount" in editor.settings_status
    assert scene.state.renderer.mode == "instanced" and scene.state.pool.threads == 2  # nothing applied
    assert editor.requested == scene.state.settings  # the editor shows what is in force
    scene.frame()
    assert scene.stats.instances == drawn


def test_inspector_edits_go_through_the_world_checks(scene):
    scene.frame()
    editor = scene.session.editor
    world = scene.state.world
    light = int(world.query(PointLight, write=()).entities()[0])
    editor.set(world, light, PointLight, intensity=3.5)
    assert world.get(light, PointLight).intensity == pytest.approx(3.5)
    cam = int(world.query(Camera, write=()).entities()[0])
    editor.set(world, cam, Camera, far=50.0)
    editor.set(world, cam, Camera, near=60.0)  # beyond far: refused, nothing changes
    assert "near" in editor.status and world.get(cam, Camera).near < 1
    added = editor.add_light(world)
    cube = editor.add_cube(world)
    assert world.has(added, PointLight) and world.has(cube, Mesh)
    editor.selected = cube
    scene.frame()  # the inspector draws the new cube
    assert editor.status == ""


def test_browser_filters_and_stays_bounded_for_large_worlds(scene):
    world = scene.state.world
    world.spawn_batch(200_000, Transform(position=np.zeros((200_000, 3))))
    editor = scene.session.editor
    editor.browser.search = ""
    ids = editor.filtered_ids(world)
    assert len(ids) == world.entities().size
    assert editor.filtered_ids(world) is ids  # cached while nothing changes
    names = editor.component_names(world)
    editor.browser.component = names.index("PointLight")
    assert len(editor.filtered_ids(world)) == 6
    editor.browser.component = 0
    editor.browser.search = str(int(ids[-1]) & 0xFFFFFFFF)
    assert editor.filtered_ids(world).tolist() == [int(ids[-1])]
    editor.browser.search = ""
    scene.frame()
    # the clipper: only the rows on screen became vertices
    assert scene.session.renderer.counts.vertices < 60_000


def test_font_atlas_updates_and_teardown_stay_validation_clean(scene):
    from imgui_bundle import imgui

    scene.frame()
    textures = list(imgui.get_platform_io().textures)
    assert textures and all(t.status == imgui.ImTextureStatus.ok for t in textures)
    # text at a new size makes ImGui 1.92 bake new glyphs: the backend uploads the changed rects
    original = scene.session.editor.draw

    def big_text(world, stats):
        original(world, stats)
        imgui.begin("big")
        imgui.push_font(None, 48.0)
        imgui.text("Large glyphs 0123")
        imgui.pop_font()
        imgui.end()

    scene.session.editor.draw = big_text
    for _ in range(3):
        scene.frame()
    assert scene.gpu.target.pixels()[..., :3].max() > 200


def test_yaw_pitch_roll_round_trip():
    rng = np.random.default_rng(3)
    for _ in range(200):
        angles = rng.uniform(-3.0, 3.0), rng.uniform(-1.5, 1.5), rng.uniform(-3.0, 3.0)
        q = yaw_pitch_roll_quat(*angles)
        q2 = yaw_pitch_roll_quat(*yaw_pitch_roll(q))
        assert min(np.abs(q - q2).max(), np.abs(q + q2).max()) < 1e-9
    assert yaw_pitch_roll_quat(0.4, -0.2, 0.0) == pytest.approx(yaw_pitch_quat(0.4, -0.2))
    assert yaw_pitch_roll(yaw_pitch_quat(0.0, math.pi / 2))[1] == pytest.approx(math.pi / 2)


def test_windowed_editor_under_xvfb(tmp_path):
    from ecs_engine.app.window import open_glfw, run_windowed

    glfw = open_glfw()
    if glfw is None:
        pytest.skip("no display (run the suite under xvfb-run)")
    result = run_windowed(
        RunOptions(
            scene="grid100",
            width=W,
            height=H,
            frames=8,
            validate=True,
            quiet=True,
            headless=False,
            editor=True,
            scenes=("grid100", "cube"),
            perf_json=str(tmp_path / "w.json"),
        ),
        glfw,
    )
    assert result.frames == 8 and result.validation_messages == []
    assert json.loads((tmp_path / "w.json").read_text())["meta"]["headless"] is False


def test_ui_rate_limit_draws_the_last_ui_between_builds(scene):
    scene.frame()
    scene.frame()
    before = scene.gpu.target.pixels()[20:300, 20:300, :3].astype(int)
    scene.session.min_interval_s = 60.0  # no rebuild for a minute
    builds = scene.session.builds
    scene.frame()
    scene.frame()
    assert scene.session.builds == builds and scene.session.build_ms == 0.0
    after = scene.gpu.target.pixels()[20:300, 20:300, :3].astype(int)
    # the settings window is still drawn (its background lets 6% of the moving scene through)
    assert np.abs(after - before).mean() < 2.0
    scene.session.min_interval_s = 0.0
    scene.frame()
    assert scene.session.builds == builds + 1
    assert scene.session.renderer.counts.commands > 5


def test_materials_window_and_light_sections_draw_and_edit():
    from ecs_engine.components import DirectionalLight, SpotLight
    from ecs_engine.render.assets.materials import materials

    scene = Scene("materials")
    try:
        editor = scene.session.editor
        world = scene.state.world
        library = materials(world)
        scene.frame()
        sphere = int(world.query(Mesh, write=()).entities()[0])
        sun = int(world.query(DirectionalLight, write=()).entities()[0])
        spot = world.spawn(Transform(position=(0.0, 2.0, 2.0)), SpotLight(intensity=5.0))
        for selected in (sphere, sun, spot):  # the Mesh, DirectionalLight and SpotLight sections
            editor.selected = selected
            scene.frame()
            assert editor.status == ""
        editor.set(world, spot, SpotLight, inner_angle=1.0, outer_angle=0.5)  # refused: inner >= outer
        assert "inner_angle" in editor.status and world.get(spot, SpotLight).outer_angle > 0.7
        handle = len(library) - 2  # a Cook-Torrance sphere: the sliders for metallic and roughness
        editor.show_material(handle)
        scene.frame()
        scene.frame()  # ImGui shows a tab selected by code from the next frame
        assert editor.open_tab is None and "metallic" in editor.materials.rects  # the tab was drawn
        before = scene.gpu.target.pixels()[..., :3].copy()
        assert editor.materials.apply(library, handle, {"base_color": (0.0, 1.0, 0.0, 1.0), "roughness": 0.2})
        assert library[handle].roughness == pytest.approx(0.2)
        scene.frame()
        assert (scene.gpu.target.pixels()[..., :3] != before).any()  # the edit shows on the next frame
        assert editor.materials.apply(library, handle, {"roughness": 3.0}) is None
        assert "roughness" in editor.materials.status and library[handle].roughness == pytest.approx(0.2)
        scene.frame()
        # a texture set from the panel shows on the next frame; a handle the registry lacks is refused
        from ecs_engine.render.assets.textures import Texture

        red = library.textures.add(Texture("red", np.full((16, 16, 3), (255, 0, 0), np.uint8)))
        before = scene.gpu.target.pixels()[..., :3].copy()
        assert editor.materials.apply(library, handle, {"base_color_texture": red, "normal_texture": red})
        scene.frame()
        scene.frame()  # the textures section, with its normal-scale slider, drawn for a textured material
        assert editor.materials.status == ""
        assert (scene.gpu.target.pixels()[..., :3] != before).any()
        assert editor.materials.apply(library, handle, {"occlusion_texture": 99}) is None
        assert "not a texture" in editor.materials.status
    finally:
        scene.close()


def test_a_tone_map_change_keeps_the_overlay_pipeline(scene):
    """A filmic tone map switches the target to HDR colour between frames: ImGui draws into the
    target's format either way (after the tone map, or over the direct form's scene), so its one
    pipeline is kept, and back in clamp too; validation stays clean (checked in close)."""
    from dataclasses import replace

    scene.frame()
    target = scene.state.gpu.target
    assert not target.hdr
    old = scene.session.renderer.pipeline
    scene.state.apply(replace(scene.state.settings, tone_map="aces"))
    assert target.hdr
    scene.frame()
    assert scene.session.renderer.pipeline == old
    scene.state.apply(replace(scene.state.settings, tone_map="clamp"))
    scene.frame()
    assert not target.hdr and scene.session.renderer.pipeline == old


def test_light_sections_show_and_edit_shadows():
    """The shadows scene's casting lights show their Shadow settings; an edit goes through the
    world's checks (a refused one leaves the value and shows the message); a light that stops
    casting loses its Shadow, and the image changes."""
    from ecs_engine.components import DirectionalLight, PointLight, Shadow, SpotLight

    scene = Scene("shadows")
    try:
        editor = scene.session.editor
        world = scene.state.world
        scene.frame()
        sun = int(world.query(DirectionalLight, write=()).entities()[0])
        for kind in (DirectionalLight, SpotLight, PointLight):  # each section, with its Shadow settings
            editor.selected = int(world.query(kind, write=()).entities()[0])
            scene.frame()
            assert editor.status == ""
        editor.set(world, sun, Shadow, cascades=2, bias=2.0)
        assert world.get(sun, Shadow).cascades == 2
        editor.set(world, sun, Shadow, resolution=8)  # refused: below 16 texels
        assert "resolution" in editor.status and world.get(sun, Shadow).resolution == 2048
        before = scene.gpu.target.pixels()[..., :3].copy()
        world.remove(sun, Shadow)  # what the "casts shadows" checkbox does
        scene.frame()
        scene.frame()
        assert (scene.gpu.target.pixels()[..., :3] != before).any()
    finally:
        scene.close()


def test_the_environment_settings_edit_the_worlds_environment():
    """The environment scene's sky, image-based ambient and intensity are in the "Scene and
    render" window: clicking "sky" replaces the Environment without it (the image stays loaded)
    and the background changes."""
    from ecs_engine.components import Environment

    scene = Scene("environment")
    try:
        editor = scene.session.editor
        world = scene.state.world
        for _ in range(3):
            scene.frame()
        before = world.resources[Environment]
        image = scene.state.renderer.environment.image
        shot = scene.gpu.target.pixels()[..., :3].copy()
        scene.frame(mouse=centre(editor.rects["sky"]))
        scene.frame(down=True)
        scene.frame(down=False)
        scene.frame()
        after = world.resources[Environment]
        assert after is not before and not after.sky and after.source is before.source
        assert scene.state.renderer.environment.image is image  # not loaded again
        assert (scene.gpu.target.pixels()[..., :3] != shot).any()
    finally:
        scene.close()
