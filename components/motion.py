"""Motion for the demos and benchmarks: linear and angular velocity."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

from .transform import LIMIT


class Velocity(Component):
    """World units per second, within +-LIMIT as positions are (faster, one step would carry the
    entity past what float32 matrices hold)."""

    linear = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True, minimum=-LIMIT, maximum=LIMIT)


class AngularVelocity(Component):
    """World-frame rotation rate: axis times radians per second."""

    angular = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True)


class Spring(Component):
    """A damped spring pulling the entity's position toward `anchor`: force -k (x - anchor) - c v
    on a mass m, integrated by SpringSystem (which needs Velocity too). Camera follow or a bobbing
    object: move the anchor, the spring does the rest."""

    anchor = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True, minimum=-LIMIT, maximum=LIMIT)
    stiffness = Field(np.float64, default=10.0, finite=True, minimum=0.0)
    damping = Field(np.float64, default=1.0, finite=True, minimum=0.0)
    mass = Field(np.float64, default=1.0, finite=True, minimum=0.0, min_exclusive=True)
