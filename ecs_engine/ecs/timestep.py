"""Fixed-step simulation: frame time goes into an accumulator and comes out as whole steps of a
fixed length, at most `max_steps` a frame; `alpha` says how far the frame lies between the last
two steps, for interpolated rendering.

A hitch of several seconds therefore costs at most `max_steps` steps, each as short as always, so
neither the frame nor the motion explodes; the time beyond the cap is dropped (and counted), the
simulation falling behind the wall clock instead of spiralling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class Interpolation:
    """World resource for the frame: render at prev + alpha (current - prev), alpha in [0, 1)."""

    alpha: float = 1.0


class FixedTimestep:
    def __init__(self, step: float = 1.0 / 60.0, max_steps: int = 8) -> None:
        if not (math.isfinite(step) and step > 0):
            raise ValueError(f"the fixed step must be a positive number of seconds, got {step!r}")
        if max_steps < 1:
            raise ValueError(f"max_steps must be at least 1, got {max_steps!r}")
        self.step = float(step)
        self.max_steps = int(max_steps)
        self.accumulator = 0.0
        self.steps = 0  # taken so far
        self.dropped_s = 0.0  # frame time thrown away by the cap

    def advance(self, frame_dt: float) -> int:
        """Add a frame's time; return how many fixed steps to run now."""
        frame_dt = float(frame_dt)
        if not (math.isfinite(frame_dt) and frame_dt >= 0):
            raise ValueError(f"a frame's time must be finite and >= 0, got {frame_dt!r}")
        self.accumulator += frame_dt
        n = int(self.accumulator // self.step)
        self.accumulator -= n * self.step
        if n > self.max_steps:
            self.dropped_s += (n - self.max_steps) * self.step
            n = self.max_steps
        self.steps += n
        return n

    @property
    def alpha(self) -> float:
        return min(max(self.accumulator / self.step, 0.0), 1.0)
