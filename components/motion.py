"""Motion for the demos and benchmarks: linear and angular velocity."""

from __future__ import annotations

import numpy as np

from ecs_engine.schema import Component, Field


class Velocity(Component):
    """World units per second."""

    linear = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True)


class AngularVelocity(Component):
    """World-frame rotation rate: axis times radians per second."""

    angular = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True)
