"""The world's surroundings (issue 15): a resource, not a component, as there is one per world:
`world.resources[Environment] = Environment("sky.hdr")`.

`source` is an equirectangular image (a Radiance `.hdr` file, linear, or an 8-bit image, sRGB),
six face images in the order +X, -X, +Y, -Y, +Z, -Z, or pixels (render/lighting/environment_maps.py's
load_cube says which shapes). With an Environment:
- `sky`: it is drawn behind everything (where no mesh is);
- materials with `reflectivity` or `refraction` show it (render/assets/materials.py);
- `ambient`: it lights every surface instead of the flat ambient colour: diffuse light from its
  spherical harmonics, and for Cook-Torrance materials the specular reflection of its mip chain;
- `intensity` scales all of it (its pixels are radiance, as lights' intensities are);
- `size`: the cube faces' side in texels (a power of two; default: from the image).
Changing the resource (a new Environment object) loads it again.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

EnvironmentSource = str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | np.ndarray


@dataclass(frozen=True, eq=False)
class Environment:
    source: Any  # EnvironmentSource
    intensity: float = 1.0
    sky: bool = True
    ambient: bool = True
    size: int | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.intensity, (int, float, np.number)) and math.isfinite(self.intensity)):
            raise ValueError(f"Environment intensity must be a finite number, got {self.intensity!r}")
        if self.intensity < 0:
            raise ValueError(f"Environment intensity must be at least 0, got {self.intensity!r}")
        object.__setattr__(self, "intensity", float(self.intensity))
        if self.size is not None and (
            isinstance(self.size, bool) or not isinstance(self.size, (int, np.integer)) or self.size < 1
        ):
            raise ValueError(f"Environment size must be a positive int or None, got {self.size!r}")
        for name in ("sky", "ambient"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f"Environment {name} must be True or False, got {getattr(self, name)!r}")
