"""The editor's scene interaction (issue 16): a click in the scene selects what is drawn under
it, the gizmo drags the selection and each drag undoes and redoes as one step, the browser finds
entities by name, and the docked layout is kept between runs."""

from __future__ import annotations

import numpy as np
from test_editor import H, Scene, W

from ecs_engine.components import Name, Transform
from ecs_engine.render.picking import pick


def central_hit(scene):
    """A point of the Scene window with an entity drawn under it, and that entity (picked in
    the viewport's own pixels: its image is the whole view, no region)."""
    editor, world = scene.session.editor, scene.state.world
    x0, y0, w, h = editor.scene.view()
    for fy in np.linspace(0.3, 0.7, 9):
        for fx in np.linspace(0.3, 0.7, 9):
            hit = pick(world, scene.gpu.meshes, fx * w, fy * h, w, h)
            if hit is not None:
                return (x0 + fx * w, y0 + fy * h), hit.entity
    raise AssertionError("nothing drawn in the Scene window")


def click(scene, at) -> None:
    scene.frame(mouse=at)
    scene.frame(down=True)
    scene.frame(down=False)


def test_a_click_in_the_scene_selects_what_is_drawn_there_not_through_a_panel(scene):
    editor = scene.session.editor
    for _ in range(3):
        scene.frame()
    at, entity = central_hit(scene)
    scene.frame(mouse=at)
    assert scene.io.want_capture_mouse and editor.scene.hovered  # ImGui's window, yet the scene's
    click(scene, at)
    assert editor.selected == entity and editor.picked == entity
    editor.selected = None
    # the settings panel covers the scene's left: a click on it picks nothing behind it, not
    # even a cube put where the scene's projection continues under the panel
    from ecs_engine.components import Mesh
    from ecs_engine.render.picking import pixel_ray

    world = scene.state.world
    at = (editor.dock.central[0] / 2, H / 2)
    origin, direction = pixel_ray(world, *at, W, H, editor.dock.region(W, H))
    behind = world.spawn(Transform(position=origin + 6.0 * direction), Mesh(handle=0))
    scene.frame()
    assert pick(world, scene.gpu.meshes, *at, W, H, editor.dock.region(W, H)).entity == behind
    click(scene, at)
    assert editor.selected is None


def key_chord(scene, *keys) -> None:
    for key in keys:
        scene.io.add_key_event(key, True)
    scene.frame()
    for key in reversed(keys):
        scene.io.add_key_event(key, False)
    scene.frame()


def test_the_gizmo_drags_the_selection_and_undo_redo_restore_it(scene):
    from imgui_bundle import imgui

    editor, world = scene.session.editor, scene.state.world
    for _ in range(3):
        scene.frame()
    at, entity = central_hit(scene)
    click(scene, at)
    assert editor.selected == entity
    before = world.get(entity, Transform).position.copy()
    # the translate gizmo's centre handle moves the selection in the screen's plane
    from ecs_engine.render.frame.camera import camera_matrices

    x0, y0, w, h = editor.scene.view()  # the gizmo's rectangle: the viewport's plain projection
    cam = camera_matrices(world, w / h)
    view = np.asarray(cam.view, np.float64)[:3, :3] @ (before - cam.position)
    clip = np.asarray(cam.projection, np.float64) @ np.r_[view, 1.0]
    handle = (x0 + (clip[0] / clip[3] + 1) * 0.5 * w, y0 + (clip[1] / clip[3] + 1) * 0.5 * h)
    scene.frame(mouse=handle)
    scene.frame(down=True)
    for dx in (10, 20, 30, 40):
        scene.frame(mouse=(handle[0] + dx, handle[1]))
    scene.frame(down=False)
    scene.frame()  # the step closes the frame after the release
    after = world.get(entity, Transform).position.copy()
    right = np.asarray(cam.inverse_view, np.float64)[:3, 0]
    assert (after - before) @ right > 0.05  # moved to the screen's right
    assert len(editor.history.undo_steps) == 1  # the whole drag: one step
    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.z)
    np.testing.assert_allclose(world.get(entity, Transform).position, before)
    key_chord(scene, imgui.Key.mod_ctrl, imgui.Key.y)
    np.testing.assert_allclose(world.get(entity, Transform).position, after)


def test_the_browser_finds_entities_by_name(scene):
    editor, world = scene.session.editor, scene.state.world
    ids = world.query(Transform).entities()
    world.add(ids[3], Name(value="Red Ship"))
    world.add(ids[5], Name(value="blue ship"))
    editor.browser.search = "SHIP"
    found = editor.filtered_ids(world)
    assert sorted(found.tolist()) == sorted([int(ids[3]), int(ids[5])])
    world.set(ids[5], Name(value="rock"))
    assert editor.filtered_ids(world).tolist() == [int(ids[3])]  # a renamed entity drops out


def test_the_docked_layout_is_kept_between_runs(config_home, monkeypatch):
    """A window's editor keeps the layout (a headless one leaves editor.ini alone: test_user_dirs)."""
    from imgui_bundle import imgui

    from ecs_engine.app import editor_dock

    monkeypatch.setattr(editor_dock, "in_a_window", lambda io: True)
    first = Scene()
    try:
        for _ in range(2):
            first.frame()
        layout = first.session.editor.dock
        assert layout.path is not None and layout.path.parent.parent == config_home
        node = imgui.internal.dock_builder_get_node(layout.id)
        assert node is not None and node.is_split_node()
        # move the Inspector into the settings' node, as a user would by dragging its tab
        settings = imgui.internal.find_window_by_name("Scene and render")
        imgui.internal.dock_builder_dock_window("Inspector", settings.dock_id)
        first.frame()
        first.frame()
    finally:
        first.close()  # destroying the context writes the layout
    assert "[Docking]" in layout.path.read_text()
    second = Scene()
    try:
        for _ in range(2):
            second.frame()
        inspector = imgui.internal.find_window_by_name("Inspector")
        settings = imgui.internal.find_window_by_name("Scene and render")
        assert inspector.dock_id == settings.dock_id != 0
    finally:
        second.close()
    layout.path.unlink()  # the next tests get the default layout again


def test_the_hierarchy_window_shows_the_tree_and_a_drag_reparents(scene):
    """Two parents with a child each: the tree lists them; dragging one parent onto the other's
    child makes it that child's child, and it stays where it was in the world."""
    from ecs_engine.components import Parent, WorldMatrix

    editor, world = scene.session.editor, scene.state.world
    ids = world.query(Transform).entities()
    a, b, c, d = (int(e) for e in ids[:4])
    world.add(b, Parent(entity=a))
    world.add(d, Parent(entity=c))
    world.add(a, Name(value="first"))
    # the Hierarchy tab is behind the Entities one: bring it forward
    from imgui_bundle import imgui

    for _ in range(2):
        scene.frame()
    imgui.set_window_focus("Hierarchy")
    for _ in range(2):
        scene.frame()
    tree = editor.tree
    assert set(tree.roots) == {a, c} and tree.below[a] == [b] and tree.below[c] == [d]
    world_before = np.array(world.get(c, Transform).position)  # a root: its Transform is its world
    source, target = tree.rects[str(c)], tree.rects[str(b)]
    start = ((source[0] + source[2]) / 2, (source[1] + source[3]) / 2)
    end = ((target[0] + target[2]) / 2, (target[1] + target[3]) / 2)
    scene.frame(mouse=start)
    scene.frame(down=True)
    for f in np.linspace(0.2, 1.0, 5):
        scene.frame(mouse=(start[0] + f * (end[0] - start[0]), start[1] + f * (end[1] - start[1])))
    scene.frame(down=False)
    scene.frame()
    assert world.get(c, Parent).entity == b
    np.testing.assert_allclose(world.get(c, WorldMatrix).matrix[:3, 3], world_before, atol=1e-6)


def test_the_gizmo_draws_over_the_scene_not_in_imguis_fallback_window(scene):
    """ImGuizmo with no draw list draws into the current window: outside every window that was
    ImGui's fallback "Debug" window, which then showed (and clipped the gizmo to itself)."""
    from imgui_bundle import imgui

    editor, world = scene.session.editor, scene.state.world
    scene.frame()
    scene.frame()
    window = imgui.internal.find_window_by_name("Scene")
    bare = window.draw_list.vtx_buffer.size()  # the image alone
    lists = imgui.get_draw_data().cmd_lists_count  # an empty background list is not among them
    editor.selected = int(world.query(Transform).entities()[0])
    scene.frame()
    scene.frame()
    debug = imgui.internal.find_window_by_name("Debug##Default")
    assert debug is None or not debug.was_active
    # the gizmo is in the Scene window's list: over its image, clipped to it
    window = imgui.internal.find_window_by_name("Scene")
    assert window.draw_list.vtx_buffer.size() > bare + 100
    assert imgui.get_draw_data().cmd_lists_count == lists  # nothing in the background list
