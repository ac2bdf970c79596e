"""Skinning on the GPU (shaders/instance_row.glsl): a posed skinned character is drawn exactly as
the same mesh posed on the CPU (animation/skins.py's skinned_positions, itself held to the
glTF formula in test_skins.py) and drawn as a still mesh, shadow on the ground included, in
every render path; unposed it is drawn in its bind pose, and moved by its hips it is drawn
where the joints took it. A pose changes the picture (the test can fail)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world
from skinned_files import tube_file

from ecs_engine import World
from ecs_engine.animation.skins import Skins, skinned_positions
from ecs_engine.components import Camera, DirectionalLight, Mesh, Name, Shadow, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.mesh_data import MeshData
from ecs_engine.render.assets.primitives import cube_mesh

W, H = 96, 80
POSE = {  # local rotations (axis, angle) and a move of the hips
    "hips": ((0.0, 0.0, 1.0), 0.15),
    "spine": ((0.0, 0.0, 1.0), 0.8),
    "head": ((1.0, 0.0, 0.0), -0.7),
}


def quat(axis, angle):
    a = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    return (*(a * math.sin(angle / 2)), math.cos(angle / 2))


def stage(gpu, world):
    """Camera, a shadow-casting sun and a ground slab."""
    grey = materials(world).add(Material("ground", "lambert", (0.7, 0.7, 0.7, 1.0)))
    ground = gpu.meshes.add(cube_mesh())
    world.spawn(Transform(position=(0.0, -0.1, 0.0), scale=(8.0, 0.2, 8.0)), Mesh(handle=ground, material=grey))
    eye = np.array([0.5, 1.6, 4.2])
    world.spawn(Transform(position=eye, rotation=look_rotation((0.0, 1.1, 0.0) - eye)), Camera(fov_y=0.9))
    sun = look_rotation((0.6, -1.0, -0.4))
    world.spawn(Transform(rotation=sun), DirectionalLight(illuminance=1.5), Shadow(resolution=512))


def entity(world, name):
    return next(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == name)


def character(gpu, tmp_path, posed):
    world = World()
    stage(gpu, world)
    scene = load_gltf(tube_file(tmp_path / "tube.gltf"), gpu.meshes.add, materials(world))
    scene.spawn(world, Transform(position=(0.1, 0.0, 0.0)))
    if posed:
        for name, (axis, angle) in POSE.items():
            t = world.get(entity(world, name), Transform)
            world.set(entity(world, name), Transform(position=t.position, rotation=quat(axis, angle), scale=t.scale))
    return world, scene


def still_copy(gpu, tmp_path, posed_world):
    """A world with the same stage and the character as a still mesh, posed on the CPU."""
    body = entity(posed_world, "body")
    handle, material = int(posed_world.get(body, Mesh).handle), int(posed_world.get(body, Mesh).material)
    mesh = gpu.meshes[handle].data
    skin = posed_world.resources.get(Skins)[0]
    matrices = skin.world_matrices(0)
    positions = skinned_positions(mesh.positions, mesh.skin.joints, mesh.skin.weights, matrices)
    blended = np.einsum("vk,vkij->vij", mesh.skin.weights.astype(np.float64), matrices[mesh.skin.joints])[:, :3, :3]
    normals = np.einsum("vij,vj->vi", np.linalg.inv(blended).transpose(0, 2, 1), mesh.normals)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    still = gpu.meshes.add(MeshData.from_arrays(positions, normals, mesh.indices, "posed"))
    world = World()
    stage(gpu, world)
    load_gltf(tube_file(tmp_path / "again.gltf"), gpu.meshes.add, materials(world))  # the same material handles
    world.spawn(Transform(), Mesh(handle=still, material=material))
    return world


@pytest.mark.parametrize("mode", ["instanced", "indirect", "per_entity"])
def test_a_posed_character_is_drawn_as_its_cpu_posed_mesh_shadow_included(tmp_path, mode):
    with headless_gpu(W, H) as gpu:
        world, _ = character(gpu, tmp_path, posed=True)
        drawn = render_world(gpu, world, mode=mode)  # (the schedule poses it: hierarchy, then skins)
        reference = render_world(gpu, still_copy(gpu, tmp_path, world), mode=mode)
        bind = render_world(gpu, character(gpu, tmp_path, posed=False)[0], mode=mode)
    differ = np.abs(drawn - reference).max(axis=2) > 24
    assert differ.sum() <= 6, differ.sum()  # rasterisation ties along an edge at most
    assert (np.abs(drawn - bind).max(axis=2) > 24).sum() > 150  # the pose shows
    lit = drawn.sum(axis=2)
    assert (lit > 0).sum() > 0.3 * W * H and lit.min() < lit.max()


def test_unposed_the_character_is_its_bind_pose_and_its_hips_carry_it(tmp_path):
    with headless_gpu(W, H) as gpu:
        world, _ = character(gpu, tmp_path, posed=False)
        bind = render_world(gpu, world)
        still = render_world(gpu, still_copy(gpu, tmp_path, world))
        world, _ = character(gpu, tmp_path, posed=False)
        hips = entity(world, "hips")
        world.set(hips, Transform(position=(1.3, 0.0, 0.0)))
        moved = render_world(gpu, world, culling="frustum")
        moved_still = render_world(gpu, still_copy(gpu, tmp_path, world), culling="frustum")
    assert (np.abs(bind - still).max(axis=2) > 24).sum() <= 6
    assert (np.abs(moved - moved_still).max(axis=2) > 24).sum() <= 6
    assert (np.abs(moved - bind).max(axis=2) > 24).sum() > 100


def test_three_characters_at_fixed_clip_times_match_their_golden_image(tmp_path):
    """demos/character.py's humanoid idling, walking and running at fixed times, casting shadows:
    the whole path (its .glb, the clips, the skin, the GPU) against an image kept in tests/golden."""
    from golden_images import SIZE, assert_close_to_golden

    from ecs_engine.animation.player import AnimationSystem
    from ecs_engine.components.animation import AnimationPlayer
    from ecs_engine.demos.character import character_file

    with headless_gpu(*SIZE) as gpu:
        world = World()
        stage(gpu, world)
        scene = load_gltf(character_file(tmp_path), gpu.meshes.add, materials(world))
        roots = scene.spawn_many(world, 3, [(-1.0, 0.0, 0.3), (0.1, 0.0, 0.0), (1.2, 0.0, -0.3)])
        handles = scene.clip_handles(world)
        for root, clip, time in zip(roots, ("idle", "walk", "run"), (0.5, 0.25, 0.2), strict=True):
            world.set(int(root), AnimationPlayer(clip=handles[clip], time=time, playing=False))
        world.run_system(AnimationSystem(), 0.0)
        pixels = render_world(gpu, world)
    assert_close_to_golden(pixels.astype(np.uint8), "characters")


def test_ray_traced_shadows_follow_the_pose_and_its_changes(tmp_path):
    """With shadows="raytraced" a skinned row's rays hit a bottom level built from this frame's
    pose (render/raytracing/deformed.py): the shadow on the ground is the still CPU-posed copy's,
    in the first pose and again after the pose changes (a refit), and not the bind pose's."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        if gpu.device.ray_tracing is None:
            pytest.skip(f"{gpu.device.info.name} has no ray-tracing pipelines")
        world, _ = character(gpu, tmp_path, posed=True)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, shadows="raytraced")
        try:
            frames = []
            for turn in (0.8, -0.6):  # the second pose refits the first one's bottom level
                spine = entity(world, "spine")
                t = world.get(spine, Transform)
                world.set(spine, Transform(position=t.position, rotation=quat((0.0, 0.0, 1.0), turn), scale=t.scale))
                default_schedule().run(world, 0.0)
                for _ in range(2):
                    renderer.render(world, readback=True)
                frames.append((gpu.target.pixels()[..., :3].astype(np.int64), still_copy(gpu, tmp_path, world)))
        finally:
            renderer.destroy()
        references = [render_world(gpu, still, shadows="raytraced") for _, still in frames]
        bind = render_world(gpu, character(gpu, tmp_path, posed=False)[0], shadows="raytraced")
    for (drawn, _), reference in zip(frames, references, strict=True):
        assert (np.abs(drawn - reference).max(axis=2) > 24).sum() <= 6
        assert (np.abs(drawn - bind).max(axis=2) > 24).sum() > 150
    assert (np.abs(frames[0][0] - frames[1][0]).max(axis=2) > 24).sum() > 150  # the two poses differ
