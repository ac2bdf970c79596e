"""Rigid-body physics on Jolt (through culverin, the `physics` extra): RigidBody and Collider
components (ecs_engine.components.physics), the PhysicsWorld resource, and PhysicsPlugin,
which steps it in the fixed stage and moves the bodies' Transforms in bulk."""

from .physics_world import PhysicsWorld
from .plugin import PhysicsPlugin, PhysicsSystem
from .queries import RayHits, ShapeHit

__all__ = ["PhysicsPlugin", "PhysicsSystem", "PhysicsWorld", "RayHits", "ShapeHit"]
