"""Light rows: the native kernel and the NumPy reference write the same rows, point and spot lights
relative to the origin and sorted far to near from the eye across several tables, directional
lights after them; directions come from rotations (local -Z) and cones as KHR_lights_punctual."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine.components import DirectionalLight, PointLight, SpotLight, Transform
from ecs_engine.ecs.world import World
from ecs_engine.maths.transform import quat_to_mat3
from ecs_engine.render.extract.frame_data import FrameExtractor
from ecs_engine.render.layouts import LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT
from ecs_engine.render.lighting import rows as light_rows
from ecs_engine.render.lighting.rows import (
    FLOATS,
    LIGHT_DTYPE,
    NO_CONE,
    DirectionalLights,
    PositionalLights,
    local_minus_z,
    spot_cones,
    write_lights,
)


def parts(rng: np.random.Generator, sizes: list[int], spots: bool = False) -> list[PositionalLights]:
    out = []
    for i, n in enumerate(sizes):
        spot = spots and i % 2 == 1
        direction = rng.normal(size=(n, 3))
        out.append(
            PositionalLights(
                rng.normal(scale=50.0, size=(n, 3)) + 1e7,
                rng.uniform(1, 9, n).astype(np.float32),
                rng.uniform(0, 1, (n, 3)).astype(np.float32),
                rng.uniform(0, 5, n).astype(np.float32),
                direction / np.linalg.norm(direction, axis=1, keepdims=True) if spot else None,
                spot_cones(rng.uniform(0, 0.3, n), rng.uniform(0.4, 1.5, n)) if spot else None,
            )
        )
    return out


@pytest.mark.parametrize("sizes, spots", [([1], False), ([7], False), ([5, 3, 40], False), ([5, 3, 40], True)])
def test_rows_are_relative_and_sorted_far_to_near(sizes, spots):
    rng = np.random.default_rng(sum(sizes))
    columns = parts(rng, sizes, spots)
    suns = [DirectionalLights(np.array([[0.0, -1.0, 0.0]] * 2), np.full((2, 3), 0.5, np.float32), np.ones(2))]
    origin = np.array([1e7, 1e7, 1e7])
    eye = np.array([3.0, -2.0, 1.0])
    total = sum(sizes)
    out = np.full((total + 2, FLOATS), np.nan, np.float32)
    assert write_lights(columns, suns, origin, eye, out) == total
    position = np.concatenate([c.position for c in columns])
    rel = position - origin
    order = np.argsort(-((rel - eye) ** 2).sum(axis=1), kind="stable")
    assert np.array_equal(out[:total, :3], rel[order].astype(np.float32))
    assert np.array_equal(out[:total, 3], np.concatenate([c.radius for c in columns])[order])
    assert np.array_equal(out[:total, 4:7], np.concatenate([c.color for c in columns])[order])
    assert np.array_equal(out[:total, 7], np.concatenate([c.intensity for c in columns])[order])
    kind = np.concatenate([np.full(len(c), LIGHT_POINT if c.direction is None else LIGHT_SPOT) for c in columns])
    assert np.array_equal(out[:total, 11], kind[order])
    direction = np.concatenate([np.zeros((len(c), 3)) if c.direction is None else c.direction for c in columns])
    np.testing.assert_array_equal(out[:total, 8:11], direction[order].astype(np.float32))
    cone = np.concatenate([np.broadcast_to(NO_CONE, (len(c), 2)) if c.cone is None else c.cone for c in columns])
    np.testing.assert_array_equal(out[:total, 12:14], cone[order].astype(np.float32))
    assert (out[:total, 14:] == 0).all()
    np.testing.assert_array_equal(
        out[total:], [[0, 0, 0, 0, 0.5, 0.5, 0.5, 1, 0, -1, 0, LIGHT_DIRECTIONAL, 0, 0, 0, 0]] * 2
    )
    reference = np.zeros_like(out)
    columns_again = light_rows._columns(columns)
    light_rows.write_positional_numpy(*columns_again, origin, eye, reference[:total])
    assert np.array_equal(out[:total], reference[:total])
    assert out.view(LIGHT_DTYPE).shape == (total + 2, 1)


def test_equal_distances_keep_their_order():
    columns = [
        PositionalLights(
            np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0, 0, 3.0]]),
            np.arange(4, dtype=np.float32),
            np.zeros((4, 3), np.float32),
            np.ones(4, np.float32),
        )
    ]
    out = np.zeros((4, FLOATS), np.float32)
    write_lights(columns, [], np.zeros(3), np.zeros(3), out)
    assert out[:, 3].tolist() == [3.0, 0.0, 1.0, 2.0]


def test_without_numba_the_reference_runs(monkeypatch):
    monkeypatch.setattr(light_rows, "_write_positional_native", None)
    test_rows_are_relative_and_sorted_far_to_near([5, 3, 40], True)


def test_a_kept_part_writes_the_values_its_views_see_now():
    """A table's point lights stay one PositionalLights from frame to frame (extract_lights): the
    kernel's columns kept on it are its views, so moved lights are written where they are now,
    and a part whose columns had to be made contiguous keeps nothing (its copies would go stale)."""
    position = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    part = PositionalLights(position, np.ones(2, np.float32), np.ones((2, 3), np.float32), np.ones(2, np.float32))
    out = np.zeros((2, FLOATS), np.float32)
    write_lights([part], [], np.zeros(3), np.zeros(3), out)
    position[:] = [[5.0, 0.0, 0.0], [0.0, 0.0, 7.0]]  # moved in place, as a system writes the column
    write_lights([part], [], np.zeros(3), np.zeros(3), out)
    assert out[:, :3].tolist() == [[0.0, 0.0, 7.0], [5.0, 0.0, 0.0]]  # far to near
    strided = np.zeros((2, 6))[:, ::2]  # every other column: not C-contiguous
    other = PositionalLights(strided, np.ones(2, np.float32), np.ones((2, 3), np.float32), np.ones(2, np.float32))
    write_lights([other], [], np.zeros(3), np.zeros(3), out)
    strided[0] = (0.0, 0.0, 9.0)
    write_lights([other], [], np.zeros(3), np.zeros(3), out)
    assert out[0, :3].tolist() == [0.0, 0.0, 9.0]


def test_local_minus_z_is_the_rotation_of_minus_z():
    rng = np.random.default_rng(4)
    q = rng.normal(size=(20, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    np.testing.assert_allclose(local_minus_z(q), quat_to_mat3(q) @ [0.0, 0.0, -1.0], atol=1e-12)
    np.testing.assert_allclose(local_minus_z(np.array([[0.0, 0.0, 0.0, 1.0]])), [[0, 0, -1]])


def test_spot_cone_falloff_matches_khr_lights_punctual():
    inner, outer = np.radians(10.0), np.radians(30.0)
    ((cos_outer, scale),) = spot_cones(np.array([inner]), np.array([outer]))
    for angle, expected in ((0.0, 1.0), (inner, 1.0), (outer, 0.0), (np.radians(40.0), 0.0)):
        t = np.clip((np.cos(angle) - cos_outer) * scale, 0, 1) ** 2
        assert t == pytest.approx(expected, abs=1e-9)
    mid = np.radians(20.0)
    t = np.clip((np.cos(mid) - cos_outer) * scale, 0, 1) ** 2
    assert 0 < t < 1


def test_extractor_reads_every_kind_from_the_world():
    world = World()
    half = np.sin(np.pi / 4)
    world.spawn(Transform(position=(1.0, 2.0, 3.0)), PointLight(intensity=2.0))
    world.spawn(
        Transform(position=(0.0, 5.0, 0.0), rotation=(-half, 0.0, 0.0, half)),  # -Z turned to -Y: down
        SpotLight(intensity=3.0, inner_angle=0.1, outer_angle=0.5),
    )
    world.spawn(Transform(rotation=(0.0, half, 0.0, half)), DirectionalLight(illuminance=4.0))  # -Z to -X
    positional, directional = FrameExtractor.lights(world)
    assert [p.direction is None for p in positional] == [True, False]
    np.testing.assert_allclose(positional[1].direction, [[0, -1, 0]], atol=1e-12)
    np.testing.assert_allclose(positional[1].cone, spot_cones(np.array([0.1]), np.array([0.5])), rtol=1e-6)
    np.testing.assert_allclose(directional[0].direction, [[-1, 0, 0]], atol=1e-12)
    assert directional[0].illuminance.tolist() == [4.0]


def test_spot_light_checks_its_cone_on_write():
    world = World()
    with pytest.raises(ValueError, match=r"inner_angle .* must be less than SpotLight\.outer_angle"):
        world.spawn(Transform(), SpotLight(inner_angle=0.6, outer_angle=0.5))
    with pytest.raises(ValueError):
        world.spawn(Transform(), SpotLight(outer_angle=2.0))  # beyond pi/2
    with pytest.raises(ValueError):
        world.spawn(Transform(), DirectionalLight(illuminance=float("nan")))
    assert len(world) == 0


def test_the_mesh_shaders_read_only_the_light_kinds_a_scene_has():
    """Point lights alone: the pipelines are specialised without the spot and directional code
    (a light is read as its first 32 bytes). A spot light added later rebuilds them, and shows."""
    import math

    from gpu_context import headless_gpu, render_world

    from ecs_engine import World
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.components import Camera, Mesh, PointLight, SpotLight, Transform
    from ecs_engine.maths.camera import look_rotation
    from ecs_engine.render.assets.primitives import plane_mesh
    from ecs_engine.render.frame.renderer import Renderer
    from ecs_engine.render.layouts import FEATURE_DIRECTIONAL_LIGHTS, FEATURE_SPOT_LIGHTS
    from ecs_engine.render.lighting.rows import light_features

    spot = PositionalLights(
        np.zeros((1, 3)), np.ones(1), np.ones((1, 3)), np.ones(1), np.zeros((1, 3)), np.ones((1, 2))
    )
    point = PositionalLights(np.zeros((1, 3)), np.ones(1), np.ones((1, 3)), np.ones(1))
    sun = DirectionalLights(np.zeros((1, 3)), np.ones((1, 3)), np.ones(1))
    assert light_features([point], []) == 0
    assert light_features([point, spot], [sun]) == FEATURE_SPOT_LIGHTS | FEATURE_DIRECTIONAL_LIGHTS
    with headless_gpu(64, 48) as gpu:
        world = World()
        world.spawn(Transform(), Mesh(handle=gpu.meshes.add(plane_mesh(20.0))))
        world.spawn(Transform(position=(-3.0, 1.0, 0.0)), PointLight(intensity=2.0, radius=4.0))
        world.spawn(
            Transform(position=(0.0, 6.0, 6.0), rotation=look_rotation((0.0, -1.0, -1.0))),
            Camera(fov_y=math.radians(60.0)),
        )
        before = render_world(gpu, world)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world)
            assert not renderer.material_features & (FEATURE_SPOT_LIGHTS | FEATURE_DIRECTIONAL_LIGHTS)
            world.spawn(
                Transform(position=(3.0, 3.0, 0.0), rotation=look_rotation((0.0, -1.0, 0.0))),
                SpotLight(intensity=20.0, radius=8.0, outer_angle=0.5),
            )
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            assert renderer.material_features & FEATURE_SPOT_LIGHTS
            after = gpu.target.pixels()[..., :3].astype(int)
        finally:
            renderer.destroy()
    assert np.abs(after - before).max() > 40  # the spot's disc on the floor
