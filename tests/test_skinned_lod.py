"""Levels of detail of skinned and morphed meshes (render/assets/mesh_lod.py, lod_deform.py): each
level vertex keeps the joints, weights and morph deltas of the original vertex it is; a level's
error counts what its collapses would fold once the mesh moves (a straight tube's rings collapse
at no rest error, but not at no error); and the indirect mode draws a skinned row's level posed
by that level's own weights (shaders/deform.glsl, the level passed through cull_row.glsl's ids)."""

from __future__ import annotations

import math

import numpy as np
from gltf_files import GltfBuilder
from gpu_context import headless_gpu
from skinned_files import tube, tube_file

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, DirectionalLight, Name, Transform
from ecs_engine.demos.character import character_file
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets import lod_deform, mesh_lod
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import materials
from ecs_engine.render.assets.mesh_data import MeshData
from ecs_engine.render.assets.mesh_lod import build_lods
from ecs_engine.render.assets.morph_targets import MorphTargets
from ecs_engine.render.assets.skin_weights import SkinWeights
from ecs_engine.render.frame.renderer import Renderer


def skinned_tube(rings=14):
    positions, normals, indices, joints, weights = tube(rings=rings)
    rng = np.random.default_rng(2)
    deltas = rng.normal(size=(2, len(positions), 3)).astype(np.float32) * 0.05
    return MeshData.from_arrays(
        positions, normals, indices.astype(np.uint32), "tube",
        skin=SkinWeights.of(joints, weights), morph=MorphTargets.of(deltas, weights=np.array([0.3, 0.0])),
    )  # fmt: skip


def test_each_level_vertex_keeps_the_weights_and_deltas_of_the_vertex_it_is():
    mesh = skinned_tube(rings=30)
    levels = build_lods(mesh)
    assert levels
    originals = {
        (tuple(j), tuple(np.round(w, 6)), tuple(np.round(d, 6).reshape(-1)))
        for j, w, d in zip(mesh.skin.joints, mesh.skin.weights, mesh.morph.positions.transpose(1, 0, 2), strict=True)
    }
    for level in levels:
        lod = level.mesh
        assert lod.skin is not None and lod.morph is not None
        assert lod.skin.vertex_count == lod.morph.vertex_count == lod.vertex_count
        np.testing.assert_array_equal(lod.morph.weights, mesh.morph.weights)
        for j, w, d in zip(lod.skin.joints, lod.skin.weights, lod.morph.positions.transpose(1, 0, 2), strict=True):
            assert (tuple(j), tuple(np.round(w, 6)), tuple(np.round(d, 6).reshape(-1))) in originals


def test_a_straight_tube_s_levels_count_what_bending_would_fold():
    """At rest the tube is straight: its middle rings collapse at no error. Its level's error is
    still at least the collapsed rings' spacing times the weight they lose (about a ring apart,
    half their weight): bent at the joint, the level would fold there."""
    positions, normals, indices, _, _ = tube(rings=30)
    still = MeshData.from_arrays(positions, normals, indices.astype(np.uint32), "still tube")
    rest_error = build_lods(still)[0].error
    skinned = build_lods(skinned_tube(rings=30))[0].error
    spacing = 2.6 / 29
    assert rest_error < 1e-3 * 2.6
    assert skinned > 0.25 * spacing


def test_the_seams_between_joints_regions_stay_in_every_level():
    """Each triangle belongs to its heaviest joint; where two joints' triangles meet, the seam's
    vertices are kept by every level (no collapse crosses from one joint's region to another)."""
    mesh = skinned_tube(rings=30)
    cut, region = lod_deform.joint_regions(mesh)
    assert cut.triangle_count == mesh.triangle_count and len(np.unique(region)) == 3
    keys = [tuple(p) for p in np.round(cut.positions, 6)]
    regions_at: dict[tuple, set] = {}
    for key, r in zip(keys, region.tolist(), strict=True):
        regions_at.setdefault(key, set()).add(r)
    seams = {key for key, rs in regions_at.items() if len(rs) > 1}
    assert len(seams) >= 2 * 10  # two rings of the tube's ten sides
    levels = build_lods(mesh)
    assert len(levels) >= 2
    for level in levels:
        kept = {tuple(p) for p in np.round(level.mesh.positions, 6)}
        assert seams <= kept, level.ratio


def test_the_character_s_coarse_level_moves_with_less_error_in_regions(tmp_path, monkeypatch):
    """The character demo's body (2,880 triangles, 24 joints): its quarter level simplified in
    its joints' regions errs about 0.11 m (its rest shape's: what moving folds is less); simplified
    across them, its collapses fold 0.19 m once it moves, which keeps the crowd's characters at
    twice the triangles (bench/animation.py)."""
    added: list[MeshData] = []
    load_gltf(character_file(tmp_path), lambda m, *a, **k: added.append(m) or len(added) - 1, materials(World()))
    body = next(m for m in added if m.skin is not None)
    quarter = build_lods(body, (0.5, 0.25))[-1]
    assert quarter.ratio == 0.25 and quarter.mesh.triangle_count < 0.27 * body.triangle_count
    assert quarter.error < 0.12
    monkeypatch.setattr(mesh_lod, "joint_regions", lambda mesh: None)
    assert build_lods(body, (0.5, 0.25))[-1].error > 0.15


def two_plates_file(tmp_path):
    """Two finely cut flat plates side by side, the left one on joint "left", the right one on
    joint "right" (one weight each): collapses inside a plate cost nothing at rest or moving, so
    the indirect mode draws a coarse level, whose vertices must take their own plate's joint."""
    n = 12
    u, v = np.meshgrid(np.linspace(0.0, 1.0, n + 1), np.linspace(0.0, 1.0, n + 1))
    grid = np.c_[u.reshape(-1), v.reshape(-1), np.zeros(u.size)]
    quads = [(r * (n + 1) + c, r * (n + 1) + c + 1) for r in range(n) for c in range(n)]
    cells = np.array([[a, b, a + n + 1, b, b + n + 1, a + n + 1] for a, b in quads]).reshape(-1)
    positions = np.r_[grid + (-1.2, -0.5, 0.0), grid + (0.2, -0.5, 0.0)].astype(np.float32)
    indices = np.r_[cells, cells + len(grid)]
    joints = np.zeros((len(positions), 4), np.uint8)
    joints[len(grid) :, 0] = 1
    weights = np.tile([1.0, 0.0, 0.0, 0.0], (len(positions), 1))
    b = GltfBuilder()
    normals = np.tile([0.0, 0.0, 1.0], (len(positions), 1))
    grey = b.material("grey", base_color=(0.8, 0.8, 0.8, 1.0), metallic=0.0, double_sided=True)
    primitive = b.primitive(positions, indices, normals=normals, material=grey, joints=joints, weights=weights)
    left, right = b.node("left"), b.node("right")
    skin = b.skin([left, right], np.stack([np.eye(4), np.eye(4)]))
    body = b.node("plates", mesh=b.mesh([primitive], name="plates"), skin=skin)
    b.scene([b.node("rig", children=[left, right, body])])
    return b.gltf(tmp_path / "plates.gltf"), len(indices) // 3


def test_the_indirect_mode_draws_a_skinned_level_posed_by_its_own_weights(tmp_path):
    path, full = two_plates_file(tmp_path)
    w, h = 96, 64
    with headless_gpu(w, h) as gpu:
        world = World()
        scene = load_gltf(path, gpu.meshes.add, materials(world))
        scene.spawn(world)
        eye = np.array([0.0, 0.0, 6.0])  # far enough for the first level (its error under a pixel)
        world.spawn(Transform(position=eye, rotation=look_rotation(-eye)), Camera(fov_y=0.9))
        world.spawn(Transform(rotation=look_rotation((0.2, -0.3, -1.0))), DirectionalLight(illuminance=2.0))
        right = next(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == "right")
        turn = (0.0, 0.0, math.sin(0.3), math.cos(0.3))  # the right plate turns about the origin
        world.set(right, Transform(rotation=turn))
        default_schedule().run(world, 0.0)
        pictures, triangles = {}, {}
        for mode, lod in (("indirect", True), ("indirect", False), ("instanced", False)):
            renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode=mode, lod=lod)
            try:
                for _ in range(3):  # (the indirect mode's counts come back a frame late)
                    stats = renderer.render(world, readback=True)
                pictures[mode, lod] = gpu.target.pixels()[..., :3].astype(np.int64)
                triangles[mode, lod] = stats.triangles
            finally:
                renderer.destroy()
    assert triangles["indirect", True] <= full // 2 < full == triangles["indirect", False]  # a coarser level drawn
    level, reference = pictures["indirect", True], pictures["instanced", False]
    assert (np.abs(level - reference).max(axis=2) > 24).sum() <= 8
    plate = np.abs(reference - reference[0, 0]).max(axis=2) > 30  # not the background
    assert plate[:, : w // 2].sum() > 60 and plate[:, w // 2 :].sum() > 60  # both plates are seen


def test_a_bent_tube_drawn_at_a_coarse_level_has_no_cracks_at_its_seams(tmp_path):
    """The skinned tube bent at its spine (its regions' seams locked, both sides of each seam the
    same vertices), drawn by the indirect mode at a coarser level: the picture is the full
    detail's but for a few pixels along the silhouette; no background shows through a seam."""
    path = tube_file(tmp_path / "tube.gltf", rings=90, sides=16)  # fine rings: its first level at 14 m
    w, h = 96, 96
    with headless_gpu(w, h) as gpu:
        world = World()
        load_gltf(path, gpu.meshes.add, materials(world)).spawn(world)
        eye = np.array([0.0, 1.3, 14.0])
        world.spawn(Transform(position=eye, rotation=look_rotation((0.0, 0.0, -1.0))), Camera(fov_y=0.35))
        world.spawn(Transform(rotation=look_rotation((0.2, -0.3, -1.0))), DirectionalLight(illuminance=2.0))
        spine = next(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == "spine")
        bind = world.get(spine, Transform)
        bend = (0.0, 0.0, math.sin(0.4), math.cos(0.4))  # 0.8 rad about z
        world.set(spine, Transform(position=bind.position, rotation=bend, scale=bind.scale))
        default_schedule().run(world, 0.0)
        pictures, triangles = {}, {}
        for mode, lod in (("indirect", True), ("instanced", False)):
            renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode=mode, lod=lod)
            try:
                for _ in range(3):
                    stats = renderer.render(world, readback=True)
                pictures[mode] = gpu.target.pixels()[..., :3].astype(np.int64)
                triangles[mode] = stats.triangles
            finally:
                renderer.destroy()
    full, level = pictures["instanced"], pictures["indirect"]
    assert triangles["indirect"] < triangles["instanced"]  # a coarser level was drawn
    background = full[0, 0]
    tube_pixels = np.abs(full - background).max(axis=2) > 30
    assert tube_pixels.sum() > 150
    through = tube_pixels & (np.abs(level - background).max(axis=2) <= 8)  # background where the tube is
    assert through.sum() <= 6
