"""Circular motion about a point: the animation of the seed scene's point lights."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

from .transform import LIMIT, Transform


class Orbit(Component):
    """OrbitSystem places the entity at center + (radius*cos(phase), height, radius*sin(phase))
    after advancing phase by angular_speed*dt. Positive speed runs from +X toward +Z, i.e.
    clockwise seen from above (+Y). The system keeps phase in [0, 2*pi) so precision holds
    however long it runs. center, radius and height stay within LIMIT, as Transform.position
    does."""

    required = (Transform,)

    center = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True, minimum=-LIMIT, maximum=LIMIT)
    radius = Field(np.float64, default=1.0, finite=True, minimum=0.0, maximum=LIMIT)
    angular_speed = Field(np.float64, default=1.0, finite=True)
    phase = Field(np.float64, default=0.0, finite=True)
    height = Field(np.float64, default=0.0, finite=True, minimum=-LIMIT, maximum=LIMIT)
