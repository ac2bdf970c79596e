"""Morph targets (render/assets/morph_targets.py, shaders/instance_row.glsl): a glTF primitive's
targets load with their default weights (the mesh's, or the node's), a clip's weights channel
animates MorphWeights, and the GPU draws a morphed mesh, and a morphed and skinned one, as the
same mesh deformed on the CPU and drawn still, shadow included, in every render mode. A broken
target is one error naming the file and the field."""

from __future__ import annotations

import json

import numpy as np
import pytest
from gltf_files import GltfBuilder
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.animation.player import AnimationSystem
from ecs_engine.animation.skins import Skins, skinned_positions
from ecs_engine.components import Camera, DirectionalLight, Mesh, Name, Shadow, Transform
from ecs_engine.components.animation import AnimationPlayer, MorphWeights
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.gltf import GltfError
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.mesh_data import MeshData
from ecs_engine.render.assets.primitives import cube_mesh

W, H = 96, 80


def blob(rings=12, sides=14):
    """A sphere (positions, normals, indices) and two targets: one swells the top, one pushes
    the +x side out."""
    theta = np.linspace(0.05, np.pi - 0.05, rings)
    phi = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    n = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], axis=-1).reshape(-1, 3)
    positions = (0.6 * n + (0.0, 0.8, 0.0)).astype(np.float32)
    quads = [(r * sides + s, r * sides + (s + 1) % sides) for r in range(rings - 1) for s in range(sides)]
    indices = np.array([[a, b, a + sides, b, b + sides, a + sides] for a, b in quads]).reshape(-1)
    swell = (np.clip(n[:, 1], 0, None)[:, None] * n * 0.5).astype(np.float32)
    push = (np.clip(n[:, 0], 0, None)[:, None] * np.array([0.6, 0.0, 0.0])).astype(np.float32)
    tilt = (np.c_[np.zeros(len(n)), np.clip(n[:, 0], 0, None) * 0.3, np.zeros(len(n))]).astype(np.float32)
    return positions, n.astype(np.float32), indices, [swell, push], [tilt, np.zeros_like(tilt)]


def blob_file(tmp_path, edit=None, node_weights=None, clip=True, skinned=False, parts=1):
    b = GltfBuilder()
    positions, normals, indices, deltas, normal_deltas = blob()
    targets = [{"POSITION": d, "NORMAL": nd} for d, nd in zip(deltas, normal_deltas, strict=True)]
    extra = {}
    if skinned:  # one joint moves the whole blob
        extra = dict(
            joints=np.zeros((len(positions), 4), np.uint8), weights=np.tile([1.0, 0, 0, 0], (len(positions), 1))
        )
    red = b.material("red", base_color=(0.9, 0.3, 0.2, 1.0), metallic=0.0)
    primitive = b.primitive(positions, indices, normals=normals, material=red, targets=targets, **extra)
    mesh = b.mesh([primitive] * parts, name="blob", weights=[0.25, 0.0])
    kids = []
    if skinned:
        bone = b.node("bone", translation=(0.0, 0.0, 0.0))
        skin = b.skin([bone], np.eye(4)[None])
        body = b.node("body", mesh=mesh, skin=skin, **({"weights": node_weights} if node_weights else {}))  # type: ignore[arg-type]
        kids = [bone, body]
    else:
        body = b.node("body", mesh=mesh)
        kids = [body]
    if node_weights is not None and not skinned:
        b.json["nodes"][body]["weights"] = node_weights
    if clip:
        b.animation([(body, "weights", [0.0, 1.0, 2.0], [0.0, 0.0, 1.0, 0.5, 0.0, 1.0], "LINEAR")], name="pulse")
    b.scene([b.node("thing", children=kids)])
    path = b.gltf(tmp_path / "blob.gltf")
    if edit is not None:
        document = json.loads(path.read_text())
        edit(document)
        path.write_text(json.dumps(document))
    return path


def entity(world, name):
    return next(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == name)


def test_targets_load_with_default_weights_and_a_clip_animates_them(tmp_path):
    meshes = []
    world = World()
    scene = load_gltf(blob_file(tmp_path), lambda m: meshes.append(m) or len(meshes) - 1, materials(world))
    root = scene.spawn(world, play="pulse")
    mesh = meshes[0]
    assert mesh.morph is not None and mesh.morph.count == 2 and np.allclose(mesh.morph.weights, [0.25, 0.0])
    blob_entity = entity(world, "body")
    assert np.allclose(world.get(blob_entity, MorphWeights).weights, [0.25, 0, 0, 0, 0, 0, 0, 0])
    system = AnimationSystem()
    for t, want in ((0.5, [0.5, 0.25]), (1.0, [1.0, 0.5]), (1.5, [0.5, 0.75])):
        world.set(root, AnimationPlayer, time=t, playing=False)
        world.run_system(system, 0.0)
        assert np.allclose(world.get(blob_entity, MorphWeights).weights[:2], want), t
    # the morphed mesh's bounds hold every vertex at full weights
    full = mesh.positions + mesh.morph.positions.sum(axis=0)
    assert (np.linalg.norm(full - mesh.center, axis=1) <= mesh.radius + 1e-5).all()
    meshes.clear()
    world = World()
    load_gltf(
        blob_file(tmp_path, node_weights=[0.0, 0.8], clip=False), lambda m: meshes.append(m) or 0, materials(world)
    ).spawn(world)
    assert np.allclose(world.get(entity(world, "body"), MorphWeights).weights[:2], [0.0, 0.8])  # the node's win


def test_the_parts_of_a_node_of_several_primitives_follow_its_animated_weights(tmp_path):
    from ecs_engine.components import Parent

    world = World()
    scene = load_gltf(blob_file(tmp_path, parts=2), lambda m: 0, materials(world))
    root = scene.spawn(world, play="pulse")
    node = entity(world, "body")
    children = world.query(Parent, MorphWeights).entities()
    parts = [int(e) for e in children if int(world.get(int(e), Parent).entity) == node]
    assert len(parts) == 2
    world.set(root, AnimationPlayer, time=1.5, playing=False)
    world.run_system(AnimationSystem(), 0.0)
    for e in (node, *parts):
        assert np.allclose(world.get(e, MorphWeights).weights[:2], [0.5, 0.75]), e


def stage(gpu, world):
    grey = materials(world).add(Material("ground", "lambert", (0.6, 0.6, 0.6, 1.0)))
    world.spawn(
        Transform(position=(0.0, -0.1, 0.0), scale=(6.0, 0.2, 6.0)),
        Mesh(handle=gpu.meshes.add(cube_mesh()), material=grey),
    )
    eye = np.array([0.8, 1.5, 3.0])
    world.spawn(Transform(position=eye, rotation=look_rotation((0.0, 0.8, 0.0) - eye)), Camera(fov_y=0.9))
    world.spawn(
        Transform(rotation=look_rotation((0.5, -1.0, -0.3))), DirectionalLight(illuminance=1.2), Shadow(resolution=512)
    )


def still_copy(gpu, tmp_path, world, weights, skinned):
    """The stage and the blob deformed on the CPU (morphed, then skinned) as a still mesh."""
    body = entity(world, "body")
    handle, material = int(world.get(body, Mesh).handle), int(world.get(body, Mesh).material)
    mesh = gpu.meshes[handle].data
    positions, normals = mesh.morph.applied(weights, mesh.positions.astype(np.float64), mesh.normals.astype(np.float64))
    if skinned:
        matrices = world.resources.get(Skins)[0].world_matrices(0)
        positions = skinned_positions(positions, mesh.skin.joints, mesh.skin.weights, matrices)
        normals = normals @ np.linalg.inv(matrices[0][:3, :3])  # one joint: its inverse transpose
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    else:
        model = world.get(body, Transform)
        positions = positions + model.position
    still = gpu.meshes.add(MeshData.from_arrays(positions, normals, mesh.indices, "deformed"))
    copy = World()
    stage(gpu, copy)
    load_gltf(blob_file(tmp_path / "again"), gpu.meshes.add, materials(copy))
    copy.spawn(Transform(), Mesh(handle=still, material=material))
    return copy


@pytest.mark.parametrize(
    ("mode", "skinned"), [("instanced", False), ("indirect", False), ("per_entity", False), ("instanced", True)]
)
def test_a_morphed_mesh_is_drawn_as_its_cpu_morphed_copy(tmp_path, mode, skinned):
    (tmp_path / "again").mkdir()
    with headless_gpu(W, H) as gpu:
        world = World()
        stage(gpu, world)
        scene = load_gltf(blob_file(tmp_path, skinned=skinned, clip=False), gpu.meshes.add, materials(world))
        scene.spawn(world)
        weights = np.array([0.9, 0.7])
        world.set(entity(world, "body"), MorphWeights(weights=np.r_[weights, np.zeros(6)]))
        if skinned:
            world.set(
                entity(world, "bone"),
                Transform(position=(0.3, 0.1, 0.0), rotation=(0.0, 0.0, np.sin(0.3), np.cos(0.3))),
            )
        drawn = render_world(gpu, world, mode=mode, lod=False)  # (a still copy would take coarser levels)
        reference = render_world(gpu, still_copy(gpu, tmp_path, world, weights, skinned), mode=mode, lod=False)
        world.set(entity(world, "body"), MorphWeights(weights=np.zeros(8)))
        rest = render_world(gpu, world, mode=mode, lod=False)
    assert (np.abs(drawn - reference).max(axis=2) > 24).sum() <= 8
    assert (np.abs(drawn - rest).max(axis=2) > 24).sum() > 60  # the weights show


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda d: d["meshes"][0]["primitives"][0].update(targets=[{}] * 9), "targets: has 9 morph targets"),
        (lambda d: d["meshes"][0]["primitives"][0].update(targets="x"), "targets: is not a non-empty array"),
        (lambda d: d["meshes"][0].update(weights=[1.0]), "meshes[0].weights"),
        (
            lambda d: d["accessors"][d["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]].update(count=3),
            "targets[0].POSITION",
        ),
    ],
)
def test_a_broken_target_is_one_error_naming_the_file_and_the_field(tmp_path, edit, field):
    path = blob_file(tmp_path, edit, clip=False)
    with pytest.raises(GltfError) as caught:
        load_gltf(path, lambda m: 0, materials(World()))
    assert str(path) in str(caught.value) and field in str(caught.value), str(caught.value)
