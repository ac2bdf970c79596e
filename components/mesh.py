"""What an entity looks like: a handle into the renderer's mesh registry and a material id."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

from .transform import ModelMatrix


class Mesh(Component):
    """A mesh is uploaded once and shared: entities hold only its handle. Anything drawn needs
    matrices, so a Mesh brings a ModelMatrix with it."""

    required = (ModelMatrix,)

    handle = Field(np.uint32, default=0)
    material = Field(np.uint32, default=0)
