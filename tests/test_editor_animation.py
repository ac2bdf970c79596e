"""The editor's Animation window (app/editor_animation.py): a selected joint leads to its
character's player; the skeleton is a line from each joint to its parent joint where the joints
stand; in the editor, the window shows for a selected character and the skeleton is drawn over
the Scene window. (Its controls, ImGui widgets over AnimationPlayer's fields and crossfade, are
not driven here.)"""

from __future__ import annotations

import numpy as np

from ecs_engine import World
from ecs_engine.animation.skins import SkinSystem
from ecs_engine.app.editor_animation import player_of, skeleton_segments
from ecs_engine.components import Name
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import materials
from ecs_engine.systems import HierarchySystem, TransformSystem


def _crowd(world, add_mesh, tmp_path, n=2):
    from ecs_engine.demos.character import SKELETON, character_file

    scene = load_gltf(character_file(tmp_path), add_mesh, materials(world))
    roots = scene.spawn_many(world, n, np.c_[np.arange(n) * 3.0, np.zeros(n), np.zeros(n)], play="walk")
    return scene, roots, len(SKELETON)


def _named(world, name):
    return sorted(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == name)


def test_a_joint_leads_to_its_player_and_the_skeleton_joins_joints_to_parents(tmp_path):
    world, meshes = World(), []
    _, roots, joints = _crowd(world, lambda m: meshes.append(m) or len(meshes) - 1, tmp_path)
    for system in (TransformSystem(), HierarchySystem(), SkinSystem()):
        world.run_system(system, 0.0)
    hand = _named(world, "hand.L")[1]
    assert player_of(world, hand) == int(roots[1]) and player_of(world, int(roots[0])) == int(roots[0])
    assert player_of(world, None) is None
    lines = skeleton_segments(world, int(roots[1]))
    assert lines.shape == (joints - 1, 2, 3)  # every joint but the hips has a parent joint
    assert (lines[:, :, 0] > 1.5).all()  # the second character's, three metres along x
    assert np.allclose(np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1).min(), 0.1, atol=0.06)  # bones, not zeros


def test_the_window_shows_for_a_selected_joint_s_character_and_draws_its_skeleton(tmp_path, monkeypatch):
    from imgui_bundle import imgui
    from test_editor import Scene

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    scene = Scene("cube")
    try:
        world, editor = scene.state.world, scene.session.editor
        _, roots, _ = _crowd(world, scene.gpu.meshes.add, tmp_path, n=1)
        scene.frame()
        assert imgui.internal.find_window_by_name("Animation") is None  # nothing selected
        editor.selected = _named(world, "forearm.R")[0]
        scene.frame()
        assert imgui.internal.find_window_by_name("Animation") is not None and editor.animated == int(roots[0])
        window = imgui.internal.find_window_by_name("Scene")
        bare = window.draw_list.vtx_buffer.size()
        editor.animation.show_skeleton = True
        scene.frame()
        scene.frame()
        window = imgui.internal.find_window_by_name("Scene")
        assert window.draw_list.vtx_buffer.size() >= bare + 4 * 10  # lines, a quad each
    finally:
        scene.close()
