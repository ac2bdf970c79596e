"""The editor's viewport as a render target (render/frame/viewport.py, app/editor_viewport.py) on
lavapipe with validation on: the frame's graph is drawn at the Scene window's size into the
viewport image, the image is remade only when the window target changes, the UI's id for it
survives a remake (ImGuiRenderer.update_image), a game's picking works inside the Scene window."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("imgui_bundle")

from test_editor import Scene

from ecs_engine.components import Mesh, Transform


def sized_frame(scene: Scene, size) -> None:
    """A frame whose viewport is `size` pixels, whatever the Scene window laid out."""
    s = scene.state
    s.schedule.run(s.world, 1 / 60)
    scene.session.build(s.world, scene.stats, scene.perf, 1 / 60, *scene.size)
    scene.session.viewport.size = size
    scene.stats = s.renderer.render(s.world, readback=True)


def test_the_graph_is_drawn_at_the_viewport_size_into_its_image(scene):
    viewport = scene.session.viewport
    sized_frame(scene, (400, 300))
    graph = scene.state.renderer.output.graph.graph
    described = graph.describe()
    assert described.startswith("frame graph 400x300")
    target = graph._table.by_name["target"]
    assert target.handle == viewport.target.color.handle  # the scene's output: the viewport image
    window = graph._table.by_name["window"]
    assert window.handle == scene.gpu.target.color.handle and tuple(window.extent) == (1024, 720)
    made = viewport.remade
    for w in range(300, 800, 50):  # ten sizes below the capacity: the same image
        sized_frame(scene, (w, 250))
    assert viewport.remade == made
    assert scene.state.renderer.output.graph.graph.describe().startswith("frame graph 750x250")


def test_the_scene_window_shows_the_scene_and_the_panels_only_the_background(scene):
    for _ in range(3):
        scene.frame()
    editor = scene.session.editor
    assert editor.scene.rect is not None and scene.session.viewport.size is not None
    x0, y0, x1, y1 = (round(v) for v in editor.scene.rect)
    assert scene.session.viewport.size == (x1 - x0, y1 - y0)
    image = scene.gpu.target.pixels()[..., :3].astype(int)
    inside = image[y0:y1, x0:x1]
    assert inside.std() > 5  # the scene's picture, not a flat clear
    # the scene is shaded for the Scene window's pixels alone (the panels are opaque, so that
    # shows in the frame's size, not in the pixels under them)
    graph = scene.state.renderer.output.graph.graph
    assert graph.describe().startswith(f"frame graph {x1 - x0}x{y1 - y0}")


def test_the_viewport_is_remade_when_the_window_target_changes(scene):
    viewport = scene.session.viewport
    scene.frame()
    first, made = viewport.target, viewport.remade
    ui = scene.session.renderer
    tex_id = viewport._tex_id
    window = scene.state.renderer.target
    window.recreations = getattr(window, "recreations", 0) + 1  # as a swapchain's remake says
    scene.frame()
    assert viewport.target is not first and viewport.remade == made + 1
    assert viewport._tex_id == tex_id and tex_id in ui.images  # the UI's id kept


def test_update_image_points_an_id_at_another_image(scene):
    """A registered red image shown in a UI window, then the id pointed at a green one: the
    window shows green, under the same id."""
    from imgui_bundle import imgui

    from ecs_engine.gpu.array_image import nearest_sampler
    from ecs_engine.gpu.memory import Image
    from ecs_engine.render.ui.imgui_upload import upload_rects

    device = scene.gpu.device
    vk = device.vk
    ui = scene.session.renderer
    usage = vk.VK_IMAGE_USAGE_SAMPLED_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
    images = [Image(device, 4, 4, vk.VK_FORMAT_R8G8B8A8_SRGB, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT) for _ in range(2)]
    sampler = nearest_sampler(device)
    layout = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
    try:
        for image, rgba in zip(images, ((255, 0, 0, 255), (0, 255, 0, 255))):
            pixels = np.broadcast_to(np.array(rgba, np.uint8), (4, 4, 4))
            tex = SimpleNamespace(bytes_per_pixel=4, format=0, width=4, height=4, get_pixels_array=lambda p=pixels: p)
            upload_rects(device, image.handle, tex, [(0, 0, 4, 4)], fresh=True)
        tex_id = ui.register_image(images[0].view, sampler, layout)
        shown = {}
        editor_draw = scene.session.draw

        def draw(world, stats, perf):
            editor_draw(world, stats, perf)
            imgui.set_next_window_pos((600, 60))
            imgui.begin("swatch", None, imgui.WindowFlags_.no_decoration.value)
            shown["at"] = imgui.get_cursor_screen_pos()
            imgui.image(imgui.ImTextureRef(tex_id), (32, 32))
            imgui.end()

        scene.session.draw = draw
        colours = []
        for swap in (False, True):
            if swap:
                device.wait_idle()
                ui.update_image(tex_id, images[1].view, sampler, layout)
            scene.frame()
            scene.frame()  # (a new window shows from its second frame)
            x, y = int(shown["at"].x) + 16, int(shown["at"].y) + 16
            colours.append(tuple(scene.gpu.target.pixels()[y, x, :3]))
        assert colours == [(255, 0, 0), (0, 255, 0)]
        assert tex_id in ui.images
    finally:
        device.wait_idle()
        vk.vkDestroySampler(device.handle, sampler, None)
        for image in images:
            image.destroy()


def test_a_games_picker_picks_under_the_pointer_inside_the_scene_window(scene):
    from ecs_engine.app.picker import Picker
    from ecs_engine.render.picking import pixel_ray
    from ecs_engine.systems import InputState

    for _ in range(2):
        scene.frame()
    editor, world = scene.session.editor, scene.state.world
    x0, y0, w, h = editor.scene.view()
    # a cube right under the pointer at the Scene window's middle (its own view's middle)
    origin, direction = pixel_ray(world, w / 2, h / 2, w, h)
    cube = world.spawn(Transform(position=origin + 3.0 * direction), Mesh(handle=0))
    state = InputState(mouse=(x0 + w / 2, y0 + h / 2), viewport=(float(scene.size[0]), float(scene.size[1])))
    state.view = (x0, y0, w, h)
    world.resources[InputState] = state
    hit = Picker(scene.gpu.meshes).under_pointer(world)
    assert hit is not None and hit.entity == cube
    assert np.isfinite(hit.distance)


def test_a_split_screen_world_draws_inside_the_scene_window(scene):
    """Two cameras with Viewports in the editor: their rectangles are the Scene window's halves
    (views.py draws into the renderer's target, the viewport image); validation stays clean
    (the fixture's close), the acquire's wait on the last view's submit."""
    from ecs_engine.components import Camera, Viewport, active_camera

    world = scene.state.world
    scene.frame()
    cam = active_camera(world)
    world.add(cam, Viewport(width=0.5))
    other = world.spawn(
        Transform(position=world.get(cam, Transform).position, rotation=world.get(cam, Transform).rotation),
        world.get(cam, Camera),
        Viewport(x=0.5, width=0.5),
    )
    assert other is not None
    for _ in range(3):
        scene.frame()
    w, h = scene.session.viewport.size
    drawn = [what for what, _ in scene.state.renderer.views.drawn]
    assert len(drawn) == 2
    half = w // 2
    assert drawn[0].endswith(f"into the window at (0, 0, {half}, {h})"), drawn
    assert drawn[1].endswith(f"into the window at ({half}, 0, {w - half}, {h})"), drawn
    x0, y0, x1, y1 = (round(v) for v in scene.session.editor.scene.rect)
    image = scene.gpu.target.pixels()[y0:y1, x0:x1, :3].astype(int)
    assert image[:, : (x1 - x0) // 2].std() > 5 and image[:, (x1 - x0) // 2 :].std() > 5


def test_dragging_the_splitter_resizes_the_viewport_and_the_next_frame(scene):
    for _ in range(3):
        scene.frame()
    editor = scene.session.editor
    x0, y0, _, y1 = editor.scene.rect
    w, h = scene.session.viewport.size
    start = (x0 - 2.0, (y0 + y1) / 2)  # the splitter between the left column and the Scene window
    scene.frame(mouse=start)
    scene.frame(down=True)
    for dx in (10, 20, 30, 40):
        scene.frame(mouse=(start[0] + dx, start[1]))
    scene.frame(down=False)
    assert scene.session.viewport.size == (w - 40, h)  # the left column grew by the drag (scale 1)
    described = scene.state.renderer.output.graph.graph.describe()
    assert described.startswith(f"frame graph {w - 40}x{h}")


def test_without_a_scene_window_the_scene_is_drawn_over_the_whole_window(scene):
    """The Scene window behind another tab (as closed: nothing shows it): no viewport size, the
    frame draws the window target as an editor without a dock does."""
    from imgui_bundle import imgui

    for _ in range(2):
        scene.frame()
    inspector = imgui.internal.find_window_by_name("Inspector")
    imgui.internal.dock_builder_dock_window("Scene", inspector.dock_id)
    for _ in range(3):
        scene.frame()
    assert scene.session.viewport.size is None and scene.session.editor.scene.rect is None
    graph = scene.state.renderer.output.graph.graph
    assert graph.describe().startswith(f"frame graph {scene.size[0]}x{scene.size[1]}")
    assert "window" not in graph._table.by_name
    image = scene.gpu.target.pixels()[..., :3].astype(int)
    assert image.std() > 5


def test_an_old_layout_without_the_scene_window_docks_it_in_the_central_node(config_home, monkeypatch):
    from imgui_bundle import imgui

    from ecs_engine.app import editor_dock

    monkeypatch.setattr(editor_dock, "in_a_window", lambda io: True)
    first = Scene()
    try:
        for _ in range(2):
            first.frame()
        path = first.session.editor.dock.path
    finally:
        first.close()  # writes editor.ini
    sections = path.read_text().split("\n\n")
    old = [part for part in sections if not part.startswith("[Window][Scene]")]
    assert len(old) == len(sections) - 1  # the layout as an editor before the Scene window kept it
    path.write_text("\n\n".join(old))
    second = Scene()
    try:
        for _ in range(3):
            second.frame()
        dock = second.session.editor.dock
        central = imgui.internal.dock_builder_get_central_node(dock.id)
        assert imgui.internal.find_window_by_name("Scene").dock_id == central.id_
        assert second.session.viewport.size is not None
    finally:
        second.close()
        path.unlink()


@pytest.mark.parametrize("settings", [{"msaa": 4}, {"post": frozenset({"bloom", "fxaa"})}])
def test_the_viewport_with_msaa_and_post_effects_is_validation_clean(tmp_path, settings):
    from test_editor import headless

    result = headless(tmp_path, editor=True, frames=3, **settings)  # (asserts no validation message)
    x0, y0, x1, y1 = (round(v) for v in result.editor.editor.scene.rect)
    assert result.pixels[y0:y1, x0:x1, :3].std() > 5
