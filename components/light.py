"""Point lights (position comes from the entity's Transform)."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field


class PointLight(Component):
    """Linear RGB colour, intensity multiplier and radius of influence (0 means unbounded)."""

    color = Field(np.float32, (3,), default=(1.0, 1.0, 1.0), finite=True, minimum=0.0)
    intensity = Field(np.float32, default=1.0, finite=True, minimum=0.0)
    radius = Field(np.float32, default=10.0, finite=True, minimum=0.0)
