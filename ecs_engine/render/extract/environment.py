"""Extract: the world's Environment resource (components/environment.py), or None. The object
itself is the snapshot: the GPU side (environment.py) compares it with the one it loaded."""

from __future__ import annotations

from ...components.environment import Environment
from ...ecs.world import World

READS = (Environment,)  # a system running extract_environment declares it


def extract_environment(world: World) -> Environment | None:
    found: Environment | None = world.resources.get(Environment)
    return found
