"""Cameras (position and orientation come from the entity's Transform)."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

PERSPECTIVE = 0
ORTHOGRAPHIC = 1


class Camera(Component):
    """Reverse-Z projection parameters. `far` may be +inf (an infinite far plane); NaN and
    -inf are rejected like any other non-finite value. `aspect` 0 means "follow the viewport".
    `height` is the view height of an orthographic camera."""

    projection = Field(np.uint8, default=PERSPECTIVE, maximum=ORTHOGRAPHIC)
    fov_y = Field(np.float64, default=np.radians(50.0), finite=True, minimum=0.0, min_exclusive=True,
                  maximum=np.pi - 1e-6)
    near = Field(np.float64, default=0.1, finite=True, minimum=0.0, min_exclusive=True)
    far = Field(np.float64, default=np.inf, finite=True, allow_posinf=True, minimum=0.0, min_exclusive=True)
    aspect = Field(np.float64, default=0.0, finite=True, minimum=0.0)
    height = Field(np.float64, default=10.0, finite=True, minimum=0.0, min_exclusive=True)

    @classmethod
    def check(cls, values, who):
        near, far = np.broadcast_arrays(values["near"], values["far"])
        bad = near >= far
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise ValueError(f"{who(row)}: Camera.near ({near[row]}) must be less than Camera.far ({far[row]})")
