"""Levels of detail in the indirect mode (mesh_registry.py, cull_row.glsl draw_key): made when
first asked for (the indirect path asks for the meshes it draws, never for the others), held by
its culling sphere, picked on the GPU by the rule mesh_lod.py states, full
detail with --no-lod, and plumbed through the flags and the editor's settings."""

from __future__ import annotations

import math

import numpy as np
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.cli import build_parser
from ecs_engine.app.scenes import default_schedule
from ecs_engine.app.settings import RunOptions
from ecs_engine.components import Mesh, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.assets.mesh_data import normalized
from ecs_engine.render.assets.mesh_loading import DEFAULT_MODEL, load_mesh
from ecs_engine.render.assets.mesh_lod import focal_pixels, lod_errors, lod_for_screen_size
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.frame.renderer import Renderer

W, H = 96, 64
FOV = math.radians(50.0)  # scene_kit.add_camera's


def knot(gpu) -> int:
    return gpu.meshes.add(normalized(load_mesh(DEFAULT_MODEL)))


def test_levels_are_made_when_asked_for_and_the_sphere_holds_them():
    with headless_gpu(W, H) as gpu:
        k, cube = knot(gpu), gpu.meshes.add(cube_mesh())
        levels = gpu.meshes.lods(k)
        assert gpu.meshes.lods(cube) == []  # 12 triangles: nothing to gain
        triangles = [gpu.meshes.triangles(k)] + [lod.mesh.triangle_count for lod in levels]
        assert len(levels) >= 2 and triangles == sorted(triangles, reverse=True)
        centers, radii, _ = gpu.meshes.bounds()
        for lod in levels:
            assert np.linalg.norm(lod.mesh.positions - centers[k], axis=1).max() <= radii[k] + 1e-9
        merged = gpu.meshes.merged()
        assert merged.count == 2 and merged.draw_meshes == 2 + len(levels)
        assert merged.lod_levels.tolist() == [len(levels), 0] and merged.lod_first[0] == 2
        assert (merged.index_count[2:] // 3).tolist() == triangles[1:]


def test_the_gpu_picks_each_rows_level_by_the_rule_of_mesh_lod():
    rng = np.random.default_rng(11)
    with headless_gpu(W, H) as gpu:
        k = knot(gpu)
        levels = gpu.meshes.lods(k)
        n = 60
        # straight ahead; the first ten close enough that their error shows (or the camera is inside)
        distance = np.concatenate([rng.uniform(0.05, 0.5, 10), rng.uniform(0.5, 40.0, n - 10)])
        scale = rng.uniform(0.3, 2.0, n)
        side = rng.uniform(-0.3, 0.3, (n, 2)) * distance[:, None] * 0.5
        positions = np.column_stack([side, -distance])
        world = World()
        world.spawn_batch(n, Transform(position=positions, scale=np.repeat(scale[:, None], 3, 1)), Mesh(handle=k))
        add_camera(world, eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0))
        default_schedule().run(world, 0.0)
        counts = {}
        for lod in (True, False):
            renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect", culling="none", lod=lod)
            gpu.owned.append(renderer)
            counts[lod] = renderer.render(world, readback=True)
        centers, radii, _ = gpu.meshes.bounds()
        row_radius = radii[k] * scale
        dist = np.linalg.norm(positions + centers[k] * scale[:, None], axis=1)
        level = lod_for_screen_size(lod_errors(levels), dist, row_radius, focal_pixels(FOV, H), scale)
        assert 0 < (level == 0).sum() < n and (level == len(levels)).sum() > 0  # a real mix
        per_level = np.array([gpu.meshes.triangles(k)] + [lod.mesh.triangle_count for lod in levels])
        assert counts[False].triangles == n * per_level[0]
        # float32 on the GPU against float64 here: a row on a threshold may go either way
        assert abs(counts[True].triangles - per_level[level].sum()) <= 2 * per_level[0]
        assert counts[True].triangles < 0.6 * counts[False].triangles


def test_only_meshes_drawn_in_the_indirect_mode_with_levels_on_get_them():
    """Issue 34: adding a mesh built its levels, so a scene file's unused 1M-vertex entry cost the
    editor minutes and gigabytes. Now adding builds none, nor does a frame that does not draw it,
    nor a frame drawn with --no-lod or in another mode."""
    with headless_gpu(W, H) as gpu:
        k, unused = knot(gpu), gpu.meshes.add(normalized(load_mesh(DEFAULT_MODEL), 2.0))
        assert not gpu.meshes.has_levels_built(k) and not gpu.meshes.has_levels_built(unused)
        world = World()
        world.spawn(Transform(position=(0.0, 0.0, -30.0)), Mesh(handle=k))
        add_camera(world, eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0))
        default_schedule().run(world, 0.0)
        for mode, lod in (("instanced", True), ("indirect", False)):
            renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode=mode, culling="none", lod=lod)
            gpu.owned.append(renderer)
            renderer.render(world, readback=True)
            assert not gpu.meshes.has_levels_built(k), (mode, lod)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect", culling="none", lod=True)
        gpu.owned.append(renderer)
        first = renderer.render(world, readback=True)
        assert gpu.meshes.has_levels_built(k) and not gpu.meshes.has_levels_built(unused)
        coarsest = gpu.meshes.lods(k)[-1].mesh.triangle_count  # 30 units away: the coarsest level
        assert first.triangles == coarsest and renderer.render(world, readback=True).triangles == coarsest
        merged = gpu.meshes.merged()
        assert merged.lod_levels.tolist() == [len(gpu.meshes.lods(k)), 0]


def test_lod_flag_and_settings():
    args = build_parser().parse_args(["demo", "scaling", "--mode", "indirect", "--no-lod"])
    options = RunOptions.from_flags(args, scene="scaling")
    assert options.lod is False and options.settings().lod is False
    assert RunOptions().settings().lod is True


def test_background_levels_arrive_later_and_equal_those_built_inline(monkeypatch):
    """A window's registry builds a big mesh's levels in a child process: the frame that asks goes
    on without them, and a later frame's bounds and merged buffers hold the same levels an inline
    build makes (the knot is made to count as big here)."""
    import time

    from ecs_engine.render.assets import mesh_registry
    from ecs_engine.render.assets.mesh_lod import build_lods
    from ecs_engine.render.assets.mesh_registry import MeshRegistry

    monkeypatch.setattr(mesh_registry, "BACKGROUND_TRIANGLES", 1000)
    monkeypatch.setattr(mesh_registry, "_LEVELS", mesh_registry.OrderedDict())  # no cached levels
    mesh = normalized(load_mesh(DEFAULT_MODEL), 1.5)
    with headless_gpu(W, H) as gpu:
        registry = MeshRegistry(gpu.device, background_levels=True)
        gpu.owned.append(registry)
        k = registry.add(mesh)
        registry.build_levels([k])
        assert not registry.has_levels_built(k) and registry.merged().lod_levels.tolist() == [0]
        deadline = time.monotonic() + 120.0
        while not registry.has_levels_built(k) and time.monotonic() < deadline:
            time.sleep(0.1)
            registry.bounds()  # where a frame picks up finished builds
        assert registry.has_levels_built(k)
        inline = build_lods(mesh)
        assert [lod.error for lod in registry.lods(k)] == [lod.error for lod in inline]
        assert not registry.lods(k)[0].mesh.positions.flags.writeable  # MeshData's arrays stay read-only
        assert registry.merged().lod_levels.tolist() == [len(inline)]
