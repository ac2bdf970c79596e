"""Finite but absurd values in the stock components are refused where they enter (issue 34, #7):
`Camera.near = 1e300` was accepted and printed float32 overflow warnings every frame; lights'
colours, intensities and radii, cameras' fields, shadow distances and velocities had no upper
bound either. Each is refused naming the entity and the field (on spawn, set and scene load),
and the largest and smallest values still accepted make a frame with no warning and finite
float32 arrays (extraction, shadow views, light rows and clusters: the CPU side of a frame)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import (
    ORTHOGRAPHIC,
    Camera,
    DirectionalLight,
    Mesh,
    Orbit,
    PointLight,
    SpotLight,
    Transform,
    Velocity,
)
from ecs_engine.components.shadow import Shadow
from ecs_engine.ecs.scene_file import SceneFileError
from ecs_engine.render.extract.frame_data import FrameExtractor
from ecs_engine.render.extract.shadows import extract_shadow_casters
from ecs_engine.render.lighting.clusters import cluster_grid, light_census
from ecs_engine.render.lighting.rows import write_lights
from ecs_engine.render.shadows.views import shadow_views

# (entity, component, field, value, what the message says)
ABSURD = [
    ("camera", Camera, "near", 1e300, r"must be <= 1e\+30"),
    ("camera", Camera, "near", 1e-300, r"must be >= 1e-30"),
    ("camera", Camera, "far", 1e300, r"must be <= 1e\+30 or \+inf"),
    ("camera", Camera, "fov_y", 1e-300, r"must be >= 1e-06"),
    ("camera", Camera, "aspect", 1e300, r"must be <= 1000"),
    ("camera", Camera, "aspect", 1e-300, r"must be 0 .* or >= 0.001"),
    ("camera", Camera, "height", 1e300, r"must be <= 1e\+09"),
    ("camera", Camera, "height", 1e-300, r"must be >= 1e-30"),
    ("point", PointLight, "intensity", 1e300, r"must fit in float32 \(magnitude at most 3.4e\+38\)"),
    ("point", PointLight, "radius", 1e20, r"must be <= 1e\+18"),
    ("point", PointLight, "color", 1e38, r"must be <= 1e\+06"),
    ("spot", SpotLight, "radius", 1e38, r"must be <= 1e\+18"),
    ("sun", DirectionalLight, "illuminance", 1e38, r"must be <= 1e\+20"),
    ("sun", DirectionalLight, "color", 1e30, r"must be <= 1e\+06"),
    ("sun", Shadow, "distance", 1e38, r"must be <= 1e\+09"),
    ("mesh", Transform, "scale", 1e31, r"must be <= 1e\+30"),
    ("mesh", Velocity, "linear", 1e300, r"must be <= 1e\+30"),
    ("orbit", Orbit, "radius", 1e300, r"must be <= 1e\+30"),
    ("orbit", Orbit, "center", -1e300, r"must be >= -1e\+30"),
]

# (entity, component, field, value): the extremes still accepted
EXTREMES = [
    ("camera", Camera, "near", 1e30),
    ("camera", Camera, "near", 1e-30),
    ("camera", Camera, "far", 1e30),
    ("camera", Camera, "fov_y", 1e-6),
    ("camera", Camera, "fov_y", math.pi - 1e-6),
    ("camera", Camera, "aspect", 1e3),
    ("camera", Camera, "aspect", 1e-3),
    ("camera", Camera, "height", 1e9),
    ("camera", Camera, "height", 1e-30),
    ("point", PointLight, "intensity", 3.0e38),  # a point or spot light's energy is capped in the shader
    ("spot", SpotLight, "intensity", 3.0e38),
    ("point", PointLight, "radius", 1e18),
    ("point", PointLight, "color", 1e6),
    ("spot", SpotLight, "radius", 1e18),
    ("sun", DirectionalLight, "illuminance", 1e20),
    ("sun", Shadow, "distance", 1e9),
    ("mesh", Transform, "scale", 1e30),
    ("mesh", Transform, "scale", -1e30),
    ("point", Transform, "position", 1e30),
    ("mesh", Velocity, "linear", 1e30),
    ("orbit", Orbit, "radius", 1e30),
]


def scene() -> tuple[World, dict[str, int]]:
    world = World()
    entities = {
        "mesh": world.spawn(Transform(), Mesh(handle=0), Velocity()),
        "camera": world.spawn(Transform(position=(0.4, 0.9, 3.0)), Camera(near=0.05)),
        "point": world.spawn(Transform(position=(1.5, 2.5, 2.5)), PointLight(intensity=6.0), Shadow(resolution=64)),
        "spot": world.spawn(Transform(position=(-1.5, 2.5, 2.5)), SpotLight(intensity=6.0), Shadow(resolution=64)),
        "sun": world.spawn(Transform(), DirectionalLight(), Shadow(resolution=64, cascades=2)),
        "orbit": world.spawn(Orbit(), PointLight(radius=0.0)),
    }
    return world, entities


def value_for(ct, field: str, value: float):
    shape = ct.__fields__[field].shape
    return np.full(shape, value) if shape else value


def prepare(world: World, e: int, ct, field: str) -> None:
    if ct is Camera and field == "height":  # an orthographic camera's
        world.set(e, Camera, projection=ORTHOGRAPHIC, far=100.0)


def put(world: World, e: int, ct, field: str, value: float) -> None:
    world.set(e, ct, **{field: value_for(ct, field, value)})


@pytest.mark.parametrize("target, ct, field, value, said", ABSURD)
def test_absurd_values_are_refused_naming_the_entity_and_field(target, ct, field, value, said, tmp_path):
    world, entities = scene()
    e = entities[target]
    prepare(world, e, ct, field)
    before = world.get(e, ct)
    with pytest.raises(ValueError, match=rf"^entity {e} .*: {ct.__name__}\.{field} {said}"):
        put(world, e, ct, field, value)
    assert world.get(e, ct) == before
    with pytest.raises(ValueError, match=rf"^new entity: {ct.__name__}\.{field} {said}"):
        world.spawn(ct(**{field: value_for(ct, field, value)}))
    f = ct.__fields__[field]
    if abs(value) > float(np.finfo(f.dtype).max):
        return  # beyond what the column holds: no file can hold it either
    # a scene file saved with the value (by an engine without the bound) is refused at load
    kept = (f.minimum, f.maximum, ct.check)
    f.minimum = f.maximum = None
    ct.check = classmethod(lambda cls, values, who: None)
    try:
        put(world, e, ct, field, value)
        world.save(tmp_path / "absurd.ecs")
    finally:
        f.minimum, f.maximum = kept[:2]
        ct.check = kept[2]
    with pytest.raises(SceneFileError, match=rf"{ct.__name__}\.{field} {said}"):
        World.load(tmp_path / "absurd.ecs")


def cpu_frame(world: World) -> list[np.ndarray]:
    """What a frame computes on the CPU, every NumPy warning an error; the float32 arrays made."""
    with np.errstate(all="raise"), warnings.catch_warnings():
        warnings.simplefilter("error")
        default_schedule().run(world, 1 / 60)
        data = FrameExtractor(lambda: 1).extract(world, 4 / 3, mesh_count=1, culling="frustum")
        views = shadow_views(extract_shadow_casters(world), data.camera, data.origin)
        rows = np.zeros((data.light_count, 16), np.float32)
        write_lights(data.lights, data.directional, data.origin, data.camera.position - data.origin, rows)
        bounded, _, reach = light_census(data.lights, data.directional, data.camera.position)
        grid = cluster_grid(64, 48, data.camera.near, reach, bounded)
    return [
        data.camera.projection,
        data.view,
        rows,
        np.array([grid.near, grid.scale], np.float32),
        *(c.model for c in data.chunks),
        *(np.asarray(v.view_projection, np.float32) for v in views),
    ]


@pytest.mark.parametrize("target, ct, field, value", EXTREMES)
def test_the_extremes_still_accepted_make_a_finite_frame(target, ct, field, value):
    world, entities = scene()
    prepare(world, entities[target], ct, field)
    put(world, entities[target], ct, field, value)
    for array in cpu_frame(world):
        assert np.isfinite(array).all()
    assert cpu_frame(scene()[0])  # and the plain scene, as a control
