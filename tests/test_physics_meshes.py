"""Colliders shaped by the entity's Mesh: a ball rests on a static triangle mesh, a cube's convex
hull falls and rests as a box would, and what cannot be made is one error naming the entity."""

from __future__ import annotations

import pytest
from physics_world import ball, physics_plugin, position

from ecs_engine import App, MinimalPlugins
from ecs_engine.components import Mesh, Transform
from ecs_engine.components.physics import CONVEX_HULL, DYNAMIC, MESH, SPHERE, STATIC, Collider, RigidBody


def run(setup, frames=120):
    from ecs_engine.physics import PhysicsWorld

    app = App(title="meshes").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.run(frames=frames)
    return app.world, app.world.resources[PhysicsWorld]


def meshes(world):
    from ecs_engine.render import Meshes

    return world.resources[Meshes]


def test_a_ball_rests_on_a_static_mesh_and_a_hull_falls_as_a_box():
    from ecs_engine.render import cube_mesh, plane_mesh

    made = {}

    def setup(world, dt):
        ground = meshes(world).add(plane_mesh(size=1.0, subdivisions=4))
        crate = meshes(world).add(cube_mesh())
        world.spawn(  # a 20 m plane at y = 0, scaled as it is drawn
            Transform(scale=(20.0, 1.0, 20.0)), Mesh(handle=ground), RigidBody(kind=STATIC), Collider(shape=MESH)
        )
        made["ball"] = ball(world, 3.0, x=2.0)
        made["crate"] = world.spawn(
            Transform(position=(-2.0, 3.0, 0.0), scale=(2.0, 1.0, 2.0)),
            Mesh(handle=crate),
            RigidBody(kind=DYNAMIC),
            Collider(shape=CONVEX_HULL),
        )

    world, _ = run(setup)
    assert position(world, made["ball"])[1] == pytest.approx(0.5, abs=0.03)  # its radius above the plane
    assert position(world, made["crate"])[1] == pytest.approx(0.5, abs=0.03)  # half its 1 m height


@pytest.mark.parametrize(
    ("kind", "with_mesh", "says"),
    [
        (DYNAMIC, True, "a mesh Collider is for static bodies"),
        (STATIC, False, "takes its shape from the entity's Mesh, and it has none"),
    ],
)
def test_a_mesh_collider_that_cannot_be_made_is_one_error(kind, with_mesh, says, capsys):
    from ecs_engine.render import cube_mesh

    def setup(world, dt):
        parts = [Transform(), RigidBody(kind=kind), Collider(shape=MESH)]
        if with_mesh:
            parts.append(Mesh(handle=meshes(world).add(cube_mesh())))
        world.spawn(*parts)

    with pytest.raises(SystemExit) as stop:
        run(setup, 2)
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0] and "entity " in err[0]


def test_balls_rest_on_a_height_field_at_its_height():
    import numpy as np

    from ecs_engine.components.physics import HEIGHT_FIELD, HeightField

    n, spacing = 17, 0.5
    x = np.arange(n) * spacing
    heights = np.tile(0.25 * x, (n, 1))  # rows along z, each rising along x: a 14 degree slope
    heights[:, :4] = 0.0  # a flat strip at x < 1.5 where a ball can rest
    made = {}

    def setup(world, dt):
        world.spawn(
            Transform(position=(0.0, 0.0, 0.0)),
            RigidBody(kind=STATIC),
            Collider(shape=HEIGHT_FIELD, friction=1.0),
            HeightField(heights=heights, spacing=spacing),
        )
        for name, x in (("flat", 0.7), ("hill", 6.0)):  # (z = 4: inside the grid, 8 m square)
            made[name] = world.spawn(Transform(position=(x, 4.0, 4.0)), RigidBody(), Collider(shape=SPHERE))

    world, _ = run(setup, 150)
    flat = position(world, made["flat"])
    assert flat[1] == pytest.approx(0.5, abs=0.03) and flat[0] == pytest.approx(0.7, abs=0.05)
    hill = position(world, made["hill"])
    assert hill[0] < 6.0  # it rolled down the slope, staying on the terrain's surface
    assert hill[1] == pytest.approx(0.25 * max(hill[0], 1.5) + 0.5 / np.cos(np.arctan(0.25)), abs=0.1)
