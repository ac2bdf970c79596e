"""Picking (render/picking.py): the entity under a pixel is the one drawn there. Checked against
the rendered image (each cube a flat colour), and on CPU-only cases: the nearer of two, a ray
that enters a bounding sphere but misses the mesh picks what is behind, far from the origin,
an orthographic camera, negative scale."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import ORTHOGRAPHIC, Camera, Mesh, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.picking import pick, pixel_ray, ray_triangles

W, H = 96, 64


class Registry:
    """What pick needs of a MeshRegistry, without a GPU."""

    def __init__(self, *meshes) -> None:
        self.meshes = meshes

    def bounds(self):
        return (
            np.array([m.center for m in self.meshes], np.float64),
            np.array([m.radius for m in self.meshes], np.float64),
            np.zeros(len(self.meshes), np.int64),
        )

    def __getitem__(self, handle):
        return type("GpuMesh", (), {"data": self.meshes[handle]})


def scene(camera_at=(0.0, 0.0, 6.0), offset=(0.0, 0.0, 0.0)) -> tuple[World, dict[str, int]]:
    offset = np.asarray(offset, np.float64)
    world = World()
    add_camera(world, tuple(np.add(camera_at, offset)), tuple(offset))
    ids = {
        "near": world.spawn(Transform(position=offset + (-1.0, 0.0, 1.0)), Mesh(handle=0)),
        "far": world.spawn(Transform(position=offset + (-0.5, 0.0, -2.0), scale=(2.0, 2.0, 2.0)), Mesh(handle=0)),
        "right": world.spawn(Transform(position=offset + (2.0, 0.5, 0.0), scale=(-1.0, 1.0, 1.0)), Mesh(handle=0)),
    }
    default_schedule().run(world, 0.0)
    return world, ids


def pixel_of(world: World, point) -> tuple[float, float]:
    """Where a world point lands on screen (pixel coordinates from the top left)."""
    from ecs_engine.render.frame.camera import camera_matrices

    cam = camera_matrices(world, W / H)
    view = np.asarray(cam.view, np.float64)[:3, :3] @ (point - cam.position)
    p = np.asarray(cam.projection, np.float64) @ np.r_[view, 1.0]
    return (p[0] / p[3] + 1.0) * 0.5 * W, (p[1] / p[3] + 1.0) * 0.5 * H


def test_the_nearest_drawn_entity_is_picked():
    world, ids = scene()
    registry = Registry(cube_mesh())
    x, y = pixel_of(world, np.array([-1.0, 0.0, 1.0]))
    hit = pick(world, registry, x, y, W, H)
    assert hit is not None and hit.entity == ids["near"]
    assert abs(hit.point[2] - 1.5) < 1e-6  # the near cube's front face (z = 1 + 0.5)
    x, y = pixel_of(world, np.array([0.3, 0.8, -1.0]))  # beside the near cube: the big far one
    assert pick(world, registry, x, y, W, H).entity == ids["far"]
    x, y = pixel_of(world, np.array([2.0, 0.5, 0.5]))  # mirrored (scale -1 in x): still picked
    assert pick(world, registry, x, y, W, H).entity == ids["right"]
    assert pick(world, registry, 1.0, 1.0, W, H) is None  # the corner: nothing


def test_a_ray_inside_a_bounding_sphere_but_off_the_mesh_picks_what_is_behind():
    """The near cube's sphere (radius 0.87) reaches past its corner: a ray through that gap hits
    the sphere first but no triangle, so the far cube behind it is picked."""
    world, ids = scene()
    registry = Registry(cube_mesh())
    corner = np.array([-1.0 + 0.56, 0.56, 1.0])  # outside the unit cube, inside its sphere
    origin, direction = pixel_ray(world, *pixel_of(world, corner), W, H)
    gap = origin + direction * ((1.0 - origin[2]) / direction[2])
    assert np.all(np.abs(gap[:2] - (-1.0, 0.0)) > 0.5) and np.linalg.norm(gap - (-1.0, 0.0, 1.0)) < 0.87
    assert pick(world, registry, *pixel_of(world, corner), W, H).entity == ids["far"]


def test_far_from_the_origin_and_orthographic():
    offset = np.array([1e7, -3e6, 2e7])
    world, ids = scene(offset=offset)
    registry = Registry(cube_mesh())
    hit = pick(world, registry, *pixel_of(world, offset + (-1.0, 0.0, 1.0)), W, H)
    assert hit.entity == ids["near"] and np.abs(hit.point - (offset + (-1.0, 0.0, 1.5)))[2] < 1e-3

    world = World()
    world.spawn(
        Transform(position=(0.0, 10.0, 0.0), rotation=look_rotation((0.0, -1.0, -1e-6))),
        Camera(projection=ORTHOGRAPHIC, height=8.0, near=0.1, far=50.0),
    )
    left = world.spawn(Transform(position=(-2.0, 0.0, 0.0)), Mesh(handle=0))
    right = world.spawn(Transform(position=(2.0, 0.0, 0.0)), Mesh(handle=0))
    default_schedule().run(world, 0.0)
    registry = Registry(cube_mesh())
    assert pick(world, registry, W / 2 - 2.0 / 8.0 * H, H / 2, W, H).entity == left
    assert pick(world, registry, W / 2 + 2.0 / 8.0 * H, H / 2, W, H).entity == right
    assert pick(world, registry, W / 2, H / 2, W, H) is None  # between them, straight down


def test_ray_triangles_both_sides_and_misses():
    tri = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    assert math.isclose(ray_triangles(np.array([0.2, 0.2, 5.0]), np.array([0.0, 0.0, -1.0]), tri), 5.0)
    assert math.isclose(ray_triangles(np.array([0.2, 0.2, -2.0]), np.array([0.0, 0.0, 1.0]), tri), 2.0)
    assert ray_triangles(np.array([0.8, 0.8, 5.0]), np.array([0.0, 0.0, -1.0]), tri) == math.inf
    assert ray_triangles(np.array([0.2, 0.2, 5.0]), np.array([0.0, 0.0, 1.0]), tri) == math.inf  # behind


def test_picking_agrees_with_the_rendered_image():
    """Every pixel of a small render: pick gives the cube whose flat colour is drawn there, and
    nothing where the background shows (edge pixels, where colours mix, are left out)."""
    colors = [(1.0, 0.0, 0.0, 1.0), (0.0, 1.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0)]
    with headless_gpu(W, H) as gpu:
        world = World()
        cube = gpu.meshes.add(cube_mesh())
        looks = [materials(world).add(Material(f"c{i}", "unlit", c)) for i, c in enumerate(colors)]
        add_camera(world, (0.5, 1.0, 6.0), (0.0, 0.0, 0.0))
        places = [(-1.0, 0.0, 1.0), (-0.3, 0.2, -1.5), (2.0, 0.5, 0.0)]
        ids = [world.spawn(Transform(position=p), Mesh(handle=cube, material=m)) for p, m in zip(places, looks)]
        from ecs_engine.render.frame.renderer import Renderer

        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, clear_color=(0.0, 0.0, 0.0))
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            image = gpu.target.pixels()[..., :3].astype(int)
        finally:
            renderer.destroy()
        checked = 0
        for y in range(0, H, 3):
            for x in range(0, W, 3):
                c = image[y, x]
                hit = pick(world, gpu.meshes, x + 0.5, y + 0.5, W, H)
                if c.max() < 5:
                    assert hit is None, (x, y)
                elif c.max() > 250 and np.sort(c)[1] < 5:  # a pure cube colour
                    assert hit is not None and hit.entity == ids[int(np.argmax(c))], (x, y, c)
                    checked += 1
    assert checked > 50


def test_the_compiled_sphere_pass_equals_the_numpy_one():
    from ecs_engine import native
    from ecs_engine.render import picking

    if not native.AVAILABLE:
        pytest.skip("ECS_ENGINE_NO_NUMBA set")
    rng = np.random.default_rng(4)
    n = 500
    models = np.zeros((n, 4, 4), np.float32)
    models[:, :3, :3] = rng.normal(size=(n, 3, 3))
    models[:, :3, 3] = rng.uniform(-4, 4, (n, 3))
    models[:, 3, 3] = 1.0
    centers, radii = rng.normal(size=(3, 3)), rng.uniform(0.5, 2.0, 3)
    handles = rng.integers(0, 3, n)
    origin, direction = np.array([0.0, 0.0, 30.0]), np.array([0.1, 0.05, -1.0]) / np.linalg.norm([0.1, 0.05, -1.0])
    want = picking._sphere_entries(origin, direction, models, centers[handles], radii[handles])
    got = np.empty(n)
    picking._entries_native(origin, direction, models, centers, radii, handles, got)
    assert np.isfinite(want).sum() > 10 and np.isinf(want).sum() > 10
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-6)  # float32 matrices


def test_a_skinned_character_is_picked_by_its_posed_triangles(tmp_path):
    """A tube bent over at its spine (tests/skinned_files.py): a click on the bent-over part picks
    it, and a click where its upper part stood in the bind pose picks nothing (the row's
    ModelMatrix only places the pose's sphere; the triangles are the shader's pose)."""
    from skinned_files import tube_file

    from ecs_engine.animation.skins import Skins, skinned_positions
    from ecs_engine.components import Name
    from ecs_engine.render.assets.gltf.scene import load_gltf
    from ecs_engine.render.assets.materials import Materials

    class Meshes(Registry):
        def bounds(self):  # each mesh's own sphere in its bind pose, as MeshRegistry.bounds gives
            centres = np.array([m.positions.mean(axis=0) for m in self.meshes], np.float64)
            radii = [np.linalg.norm(m.positions - c, axis=1).max() for m, c in zip(self.meshes, centres, strict=True)]
            return centres, np.array(radii), np.zeros(len(self.meshes), np.int64)

    loaded = []

    def add(mesh):
        loaded.append(mesh)
        return len(loaded) - 1

    world = World()
    add_camera(world, (0.0, 1.3, 7.0), (0.0, 1.3, 0.0))
    scene = load_gltf(tube_file(tmp_path / "tube.gltf"), add, Materials())
    scene.spawn(world)
    named = {world.get(int(e), Name).value: int(e) for e in world.query(Name).entities()}
    spine = world.get(named["spine"], Transform)
    bend = (0.0, 0.0, math.sin(0.75), math.cos(0.75))  # 1.5 rad about z: the upper part lies sideways
    world.set(named["spine"], Transform(position=spine.position, rotation=bend, scale=spine.scale))
    default_schedule().run(world, 0.0)
    meshes = Meshes(*loaded)
    body = named["body"]
    mesh = loaded[int(world.get(body, Mesh).handle)]
    matrices = world.resources.get(Skins)[0].world_matrices(0)
    posed = skinned_positions(mesh.positions, mesh.skin.joints, mesh.skin.weights, matrices)
    top = posed[mesh.positions[:, 1] > 2.0].mean(axis=0)  # on the axis of the bent-over part, far to the side
    assert top[0] < -1.0
    hit = pick(world, meshes, *pixel_of(world, top), W, H)
    assert hit is not None and hit.entity == body
    assert np.linalg.norm(posed - hit.point, axis=1).min() < 0.4  # on the posed surface
    assert pick(world, meshes, *pixel_of(world, np.array([0.0, 2.4, 0.0])), W, H) is None  # bind pose's top: empty now
