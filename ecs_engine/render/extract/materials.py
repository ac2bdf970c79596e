"""Extract: the world's Materials resource (materials.py), or a default palette for a world
without one. The frame's passes read the registry through the snapshot (FrameData.materials)."""

from __future__ import annotations

from ...ecs.world import World
from ..assets.materials import Materials

READS = (Materials,)  # a system running extract_materials declares it


def extract_materials(world: World, default: Materials) -> Materials:
    found: Materials | None = world.resources.get(Materials)
    return found if found is not None else default
