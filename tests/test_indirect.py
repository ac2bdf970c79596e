"""The indirect mode's GPU culling and draw commands: what the compute shaders keep matches the
CPU kernel and a brute-force reference, plane by plane; mirrored and several meshes are drawn
with the right commands; meshes added between frames are drawn."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, ModelMatrix, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.maths.culling import bounding_spheres, frustum_planes, spheres_visible
from ecs_engine.render.assets.mesh_data import normalized
from ecs_engine.render.assets.mesh_loading import DEFAULT_MODEL, load_mesh
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.frame.camera import camera_matrices

W, H = 64, 48


def indirect_renderer(gpu, **kw):
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect", **kw)
    gpu.owned.append(renderer)
    return renderer


def cpu_visible(world: World, gpu) -> np.ndarray:
    """Brute force from the ECS columns: each mesh entity's sphere against the frustum."""
    cam = camera_matrices(world, W / H)
    planes = frustum_planes(cam.projection, cam.view)
    out = []
    for batch in world.query(ModelMatrix, Mesh, write=()):
        handle = batch[Mesh].handle
        centers = np.array([gpu.meshes[h].data.center for h in handle], dtype=np.float64).reshape(-1, 3)
        radii = np.array([gpu.meshes[h].data.radius for h in handle], dtype=np.float64)
        c, r = bounding_spheres(batch[ModelMatrix].model, centers, radii)
        out.append(spheres_visible(c, r, planes))
    return np.concatenate(out)


def test_gpu_culling_matches_brute_force_with_two_meshes_and_mirrored_entities():
    rng = np.random.default_rng(5)
    with headless_gpu(W, H) as gpu:
        cube, knot = gpu.meshes.add(cube_mesh()), gpu.meshes.add(normalized(load_mesh(DEFAULT_MODEL)))
        world = World()
        n = 3000
        scale = rng.uniform(0.2, 1.0, size=(n, 3)) * np.where(rng.random((n, 1)) < 0.2, -1.0, 1.0)
        world.spawn_batch(
            n,
            Transform(position=rng.uniform(-40, 40, size=(n, 3)), scale=scale),
            Mesh(handle=np.where(rng.random(n) < 0.5, cube, knot)),
        )
        add_camera(world, eye=(0.0, 2.0, 25.0), target=(5.0, 0.0, 0.0))
        default_schedule().run(world, 0.0)
        renderer = indirect_renderer(gpu, chunk_rows=700)
        stats = renderer.render(world, readback=True)
        expected = int(cpu_visible(world, gpu).sum())
        assert 100 < expected < n - 100  # a real mix
        # equal but for spheres within float32 rounding of a plane
        assert abs(stats.instances - expected) <= 3
        assert stats.candidates == n and stats.chunks == 5
        assert stats.draws == 4  # (cube, knot) x (plain, mirrored): one command each
        assert gpu.target.pixels()[..., :3].max() > 30
        # counts come back without waiting on later frames: each slot reports its previous frame
        later = [renderer.render(world).instances for _ in range(3)]
        assert later[-1] == stats.instances


def test_each_plane_on_the_gpu_keeps_just_inside_and_drops_just_outside():
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        world = World()
        add_camera(world, eye=(3.0, 1.0, -2.0), target=(-4.0, 2.5, -9.0))
        default_schedule().run(world, 0.0)
        cam = camera_matrices(world, W / H)
        planes = frustum_planes(cam.projection, cam.view)
        forward = cam.inverse_view[:3, :3] @ np.array([0.0, 0.0, -1.0])
        mesh = gpu.meshes[cube].data
        size = 0.1 / mesh.radius  # a sphere of radius 0.1
        radius = 0.1
        positions = []
        for p in planes:
            n, d = p[:3], p[3]
            inner = forward * 5.0
            on_plane = inner - (np.dot(n, inner) + d) * n - mesh.center * size
            positions += [on_plane + n * radius * 0.5, on_plane - n * radius * 1.5]
        positions = np.array(positions) + cam.position
        world.spawn_batch(len(positions), Transform(position=positions, scale=(size, size, size)), Mesh(handle=cube))
        default_schedule().run(world, 0.0)
        assert cpu_visible(world, gpu).tolist() == [True, False] * len(planes)
        stats = indirect_renderer(gpu).render(world, readback=True)
        assert stats.instances == len(planes)
        everything = indirect_renderer(gpu, culling=False).render(world, readback=True)
        assert everything.instances == 2 * len(planes)


def test_a_mesh_added_between_frames_is_drawn():
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        world = World()
        world.spawn(Transform(position=(-1.0, 0.0, 0.0)), Mesh(handle=cube))
        add_camera(world, eye=(0.0, 0.5, 4.0), target=(0.0, 0.0, 0.0))
        renderer = indirect_renderer(gpu)
        default_schedule().run(world, 0.0)
        first = renderer.render(world, readback=True)
        before = gpu.target.pixels().copy()
        knot = gpu.meshes.add(normalized(load_mesh(DEFAULT_MODEL)))
        world.spawn(Transform(position=(1.0, 0.0, 0.0), scale=(0.8, 0.8, 0.8)), Mesh(handle=knot))
        default_schedule().run(world, 0.0)
        second = renderer.render(world, readback=True)
        assert (first.instances, first.draws) == (1, 1)
        assert (second.instances, second.draws) == (2, 2)
        changed = np.abs(gpu.target.pixels()[..., :3].astype(int) - before[..., :3]).max(axis=2) > 4
        # no lights: ambient only, so dim; the knot appeared on the right, the cube stayed
        assert changed[:, W // 2 + 4 :].sum() > 50 and changed[:, : W // 2 - 4].sum() == 0


def test_a_device_without_indirect_count_gets_one_clear_error(monkeypatch):
    from ecs_engine.errors import UsageError

    with headless_gpu(W, H) as gpu:
        monkeypatch.setitem(gpu.device.features, "drawIndirectCount", False)
        with pytest.raises(UsageError, match=r"lacks drawIndirectCount.*--mode instanced"):
            indirect_renderer(gpu)


def test_counts_read_back_late_survive_meshes_added_between_frames():
    """Frames that are not waited for report the slot's previous counts: read with the mesh list
    that frame had, also after meshes were added (the editor's scene switch adds them)."""
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        world = World()
        world.spawn(Transform(position=(-1.0, 0.0, 0.0)), Mesh(handle=cube))
        add_camera(world, eye=(0.0, 0.5, 4.0), target=(0.0, 0.0, 0.0))
        renderer = indirect_renderer(gpu)
        default_schedule().run(world, 0.0)
        assert [renderer.render(world).instances for _ in range(3)][-1] == 1
        for size in (0.8, 0.6):  # each time a mesh more: the key table and its buffers grow
            knot = gpu.meshes.add(normalized(load_mesh(DEFAULT_MODEL), size=size))
            world.spawn(Transform(position=(1.0, 0.0, 0.0)), Mesh(handle=knot))
            default_schedule().run(world, 0.0)
            late = [renderer.render(world) for _ in range(3)]
            assert late[0].instances == world.query(Mesh).count() - 1  # an earlier frame's count
            assert late[-1].instances == world.query(Mesh).count()
        assert renderer.render(world, readback=True).draws == 3  # one command per mesh drawn
