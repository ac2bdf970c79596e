"""Helpers of the physics tests (tests/test_physics*.py): a world stepped through App with
MinimalPlugins and PhysicsPlugin, and the bodies they build."""

from __future__ import annotations

import pytest

from ecs_engine import App, MinimalPlugins
from ecs_engine.components import Transform
from ecs_engine.components.physics import BOX, SPHERE, STATIC, Collider, RigidBody

G = 9.81


def physics_plugin(**kw):
    pytest.importorskip("culverin", reason="the physics extra (CPython 3.12+): make test-physics")
    from ecs_engine.physics import PhysicsPlugin

    return PhysicsPlugin(**{"threads": 2, **kw})


def simulate(setup, frames, **kw):
    """A world of `setup`'s bodies stepped `frames` fixed steps of 1/60 s: (world, physics)."""
    from ecs_engine.physics import PhysicsWorld

    app = App(title="physics test").add_plugins(MinimalPlugins, physics_plugin(**kw))
    app.add_startup_systems(setup)
    app.run(frames=frames)
    return app.world, app.world.resources[PhysicsWorld]


def floor(world, friction=0.5, restitution=0.0):
    return world.spawn(
        Transform(position=(0.0, -0.5, 0.0)),
        RigidBody(kind=STATIC),
        Collider(shape=BOX, size=(50.0, 0.5, 50.0), friction=friction, restitution=restitution),
    )


def ball(world, y, restitution=0.0, x=0.0, **more):
    return world.spawn(
        Transform(position=(x, y, 0.0)),
        RigidBody(),
        Collider(shape=SPHERE, size=(0.5, 0.5, 0.5), restitution=restitution),
        *more.values(),
    )


def position(world, entity):
    return world.get(entity, Transform).position


def anchor(world, at):  # a small static body that touches nothing (category 4, mask 4)
    ghost = Collider(shape=SPHERE, size=(0.1, 0.1, 0.1), category=4, mask=4)
    return world.spawn(Transform(position=at), RigidBody(kind=STATIC), ghost)
