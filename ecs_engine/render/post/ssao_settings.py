"""SSAO's settings and the camera its passes read (ssao.py says what the effect does): apart from
the passes, which import them, and from ssao.py, which adds the passes."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import UsageError

MAX_SLICES = 16
MAX_STEPS = 32


@dataclass(frozen=True)
class SsaoSettings:
    """radius: how far (metres, view space) a surface occludes; intensity: the exponent on the
    visibility (XeGTAO's "final value power": 0 turns AO off, 1 is the physical value, about 2
    the usual look); slices: screen directions per pixel; steps: depth samples on each side of
    a slice (Bevy's presets: 1x2 low, 2x2 medium, 3x3 high, 9x3 ultra); falloff: the last
    fraction of the radius over which an occluder fades out."""

    radius: float = 0.5
    intensity: float = 2.0
    slices: int = 3
    steps: int = 3
    falloff: float = 0.615

    def __post_init__(self) -> None:
        for name in ("radius", "intensity", "falloff"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise UsageError(f"SSAO {name} must be a finite number, not {value!r}")
        if self.radius <= 0:
            raise UsageError(f"SSAO radius must be positive (metres), not {self.radius!r}")
        if self.intensity < 0:
            raise UsageError(f"SSAO intensity must be 0 or more, not {self.intensity!r}")
        if not 0 < self.falloff <= 1:
            raise UsageError(f"SSAO falloff must be in (0, 1], not {self.falloff!r}")
        for name, top in (("slices", MAX_SLICES), ("steps", MAX_STEPS)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= top:
                raise UsageError(f"SSAO {name} must be a whole number from 1 to {top}, not {value!r}")


class SsaoView:
    """The camera the passes read: its projection (4 x 4, the engine's reverse-Z convention of
    maths/camera.py: perspective, orthographic or a region's off-axis one), set by the renderer
    before compile/execute. The passes' push constants (and so their keys) come from it."""

    def __init__(self, projection: Any = None) -> None:
        self._projection: np.ndarray | None = None
        if projection is not None:
            self.projection = projection

    @property
    def projection(self) -> np.ndarray:
        if self._projection is None:
            raise UsageError("SSAO has no projection: set SsaoView.projection before executing the graph")
        return self._projection

    @projection.setter
    def projection(self, matrix: Any) -> None:
        m = np.array(matrix, dtype=np.float64)
        if m.shape != (4, 4) or not np.isfinite(m).all():
            raise UsageError(f"an SSAO projection is a finite 4 x 4 matrix, not shape {m.shape}")
        if abs(np.linalg.det(m)) < 1e-30:
            raise UsageError("the SSAO projection cannot be inverted")
        m.flags.writeable = False
        self._projection = m

    def push_constants(self, settings: SsaoSettings, extent: tuple[int, int]) -> bytes:
        """The shaders' Params block (std430-compatible push constants, 112 bytes)."""
        return push_constants(self.projection, settings, extent)

    def key(self) -> bytes | None:
        return None if self._projection is None else self._projection.tobytes()


def push_constants(projection: np.ndarray, settings: SsaoSettings, extent: tuple[int, int]) -> bytes:
    """inverse projection (column-major for GLSL), lens (pixels per view unit at w = 1, the clip
    w row's z and constant terms, radius), shape (intensity, falloff), counts (slices, steps,
    `extent`: the view's rectangle at the images' corner, which the shaders take as the whole
    image: a split-screen view's depth and HDR images are the window's, larger than it)."""
    p = np.asarray(projection, dtype=np.float64)
    inverse = np.linalg.inv(p).astype(np.float32)
    lens = np.array([0.5 * p[0, 0] * extent[0], p[3, 2], p[3, 3], settings.radius], np.float32)
    shape = np.array([settings.intensity, settings.falloff, 0.0, 0.0], np.float32)
    counts = np.array([settings.slices, settings.steps, extent[0], extent[1]], np.int32)
    return inverse.T.tobytes() + lens.tobytes() + shape.tobytes() + counts.tobytes()
