"""The state of a keyboard-driven fly camera."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

from .transform import Transform


class FlyCamera(Component):
    """Yaw and pitch are the camera's state; FlyCameraSystem rebuilds Transform.rotation from
    them every frame so the orientation never drifts. Yaw turns about world +Y (0 looks down -Z,
    positive turns left), pitch about the camera's +X (positive looks up); the system wraps yaw
    and clamps pitch short of the poles. Speeds are world units per second and radians per
    second."""

    required = (Transform,)

    yaw = Field(np.float64, default=0.0, finite=True)
    pitch = Field(np.float64, default=0.0, finite=True)
    move_speed = Field(np.float64, default=5.0, finite=True, minimum=0.0, min_exclusive=True)
    turn_speed = Field(np.float64, default=1.5, finite=True, minimum=0.0, min_exclusive=True)
