"""Lights. A point or spot light's position is its entity's Transform position; a spot or
directional light shines along its Transform's local -Z axis (glTF's and Bevy's convention), so a
rotation aims it.

Units follow one convention: a white Lambert surface facing a light head-on has the radiance
`illuminance` (directional) or `intensity / distance^2` (point, spot), times the light's colour.
Physically that folds the 1/pi of a Lambert BRDF into the light: the shaders multiply every BRDF
by pi (see shaders/shading.glsl), so lights keep the brightness they had before materials.
"""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

# The largest colour component and illuminance: the shaders multiply the two and a BRDF in float32,
# and a directional light's product is not capped as a point or spot light's energy is (any
# float32 intensity works there: tests/test_numerics_render.py), so these keep it finite
# (1e6 * 1e20 * a BRDF's peak is far below float32's 3.4e38).
MAX_COLOR = 1e6
MAX_ILLUMINANCE = 1e20
# The largest radius (range): its square, which the shaders take, stays a finite float32.
MAX_RADIUS = 1e18


class PointLight(Component):
    """Linear RGB colour, intensity and radius of influence (0 means unbounded). Within the
    radius the light falls off as 1/d^2 times a window that reaches 0 at the radius."""

    color = Field(np.float32, (3,), default=(1.0, 1.0, 1.0), finite=True, minimum=0.0, maximum=MAX_COLOR)
    intensity = Field(np.float32, default=1.0, finite=True, minimum=0.0)
    radius = Field(np.float32, default=10.0, finite=True, minimum=0.0, maximum=MAX_RADIUS)


class SpotLight(Component):
    """A point light limited to a cone around the entity's -Z axis: full within `inner_angle`
    of the axis, fading (smoothly, as glTF's KHR_lights_punctual) to none at `outer_angle`
    (radians, 0 <= inner < outer <= pi/2). `radius` is its range, as PointLight's."""

    color = Field(np.float32, (3,), default=(1.0, 1.0, 1.0), finite=True, minimum=0.0, maximum=MAX_COLOR)
    intensity = Field(np.float32, default=1.0, finite=True, minimum=0.0)
    radius = Field(np.float32, default=10.0, finite=True, minimum=0.0, maximum=MAX_RADIUS)
    inner_angle = Field(np.float32, default=0.0, finite=True, minimum=0.0, maximum=np.pi / 2)
    outer_angle = Field(np.float32, default=np.pi / 4, finite=True, minimum=0.0, maximum=np.pi / 2)

    @classmethod
    def check(cls, values, who):
        inner, outer = np.broadcast_arrays(values["inner_angle"], values["outer_angle"])
        bad = inner >= outer
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"{who(row)}: SpotLight.inner_angle ({inner[row]:g}) must be less than "
                f"SpotLight.outer_angle ({outer[row]:g})"
            )


class DirectionalLight(Component):
    """Light from far away (the sun) along the entity's -Z axis: linear RGB colour and
    illuminance, the same everywhere in the scene."""

    color = Field(np.float32, (3,), default=(1.0, 1.0, 1.0), finite=True, minimum=0.0, maximum=MAX_COLOR)
    illuminance = Field(np.float32, default=1.0, finite=True, minimum=0.0, maximum=MAX_ILLUMINANCE)
