"""Shadows (issue 15): a light casts them only when its entity also has a `Shadow`, so a scene
pays only for the shadows it asks for; meshes cast and receive them unless tagged otherwise
(Bevy's `NotShadowCaster` and `NotShadowReceiver`: what most meshes want is the default).

`Shadow`'s fields, per light:
- `resolution`: texels across each shadow map (a cascade, a spot light's map, a cube face);
- `cascades` and `distance` (directional lights): the view from the camera's near plane to
  `distance` is split into that many cascades (maths/shadow_cascades.py);
- `bias` and `normal_offset`: how far a receiver's depth is pushed towards the light, and its
  position along its normal, in texels of the map, so that neither depends on the resolution;
- `filter`: SHADOW_HARD, SHADOW_PCF (the default: percentage-closer filtering) or SHADOW_PCSS
  (contact-hardening: the penumbra widens with the receiver's distance from its caster);
- `softness`: the PCF kernel's radius in texels; for PCSS the light's size in world units (a
  directional light's: its width per unit of distance, e.g. 0.02 for a soft sun).
"""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field
from ecs_engine.maths.shadow_cascades import MAX_CASCADES

SHADOW_HARD, SHADOW_PCF, SHADOW_PCSS = range(3)
# The farthest a directional light's cascades reach: cascades fitted to more fail (their planes'
# normals fall under the 1e-12 that maths/culling.py's frustum_planes_many takes as degenerate).
MAX_DISTANCE = 1e9
SHADOW_FILTERS = ("hard", "pcf", "pcss")


class Shadow(Component):
    """The light on this entity (point, spot or directional) casts shadows (see the module)."""

    resolution = Field(np.uint16, default=2048, minimum=16, maximum=8192)
    cascades = Field(np.uint8, default=MAX_CASCADES, minimum=1, maximum=MAX_CASCADES)
    distance = Field(np.float32, default=50.0, finite=True, minimum=0.0, min_exclusive=True, maximum=MAX_DISTANCE)
    bias = Field(np.float32, default=1.0, finite=True, minimum=0.0)
    normal_offset = Field(np.float32, default=1.0, finite=True, minimum=0.0)
    filter = Field(np.uint8, default=SHADOW_PCF, maximum=SHADOW_PCSS)
    softness = Field(np.float32, default=1.5, finite=True, minimum=0.0)


class NotShadowCaster(Component):
    """Tag: this mesh casts no shadow (it is left out of every shadow pass)."""


class NotShadowReceiver(Component):
    """Tag: no shadow falls on this mesh."""
