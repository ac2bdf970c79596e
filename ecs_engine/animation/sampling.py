"""Keyframe curves sampled as glTF 2.0 defines them (its Appendix C), for many times at once:
STEP holds a key's value until the next key, LINEAR interpolates (rotations by spherical linear
interpolation, the shorter way round), CUBICSPLINE is the cubic Hermite spline through each
key's value with its in- and out-tangents scaled by the interval. Before the first key the
first value holds, after the last the last; rotations come out unit length."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

STEP, LINEAR, CUBICSPLINE = "STEP", "LINEAR", "CUBICSPLINE"
INTERPOLATIONS = (STEP, LINEAR, CUBICSPLINE)


@dataclass(frozen=True)
class Curve:
    """Key `times` (strictly increasing, seconds) and their `values` (keys, *element); for
    CUBICSPLINE, `in_tangents` and `out_tangents` of the values' shape. `rotation`: the values
    are quaternions (x, y, z, w)."""

    times: np.ndarray
    values: np.ndarray
    interpolation: str = LINEAR
    rotation: bool = False
    in_tangents: np.ndarray | None = None
    out_tangents: np.ndarray | None = None

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    def sample(self, t: np.ndarray | float) -> np.ndarray:
        """The curve at times `t` (any shape): (*t.shape, *element)."""
        t = np.asarray(t, np.float64)
        times, values = self.times, self.values
        flat = t.reshape(-1)
        if len(times) == 1:
            return np.broadcast_to(values[0], (*t.shape, *values.shape[1:])).copy()
        clamped = np.clip(flat, times[0], times[-1])
        k = np.clip(np.searchsorted(times, clamped, side="right") - 1, 0, len(times) - 2)
        span = times[k + 1] - times[k]
        s = (clamped - times[k]) / span
        shape = (-1,) + (1,) * (values.ndim - 1)
        if self.interpolation == STEP:
            out = np.where((clamped >= times[-1]).reshape(shape), values[-1], values[k])
        elif self.interpolation == LINEAR:
            out = slerp(values[k], values[k + 1], s) if self.rotation else lerp(values[k], values[k + 1], s)
        else:
            assert self.in_tangents is not None and self.out_tangents is not None
            s_ = s.reshape(shape)
            d = span.reshape(shape)
            s2, s3 = s_ * s_, s_ * s_ * s_
            out = (
                (2 * s3 - 3 * s2 + 1) * values[k]
                + d * (s3 - 2 * s2 + s_) * self.out_tangents[k]
                + (-2 * s3 + 3 * s2) * values[k + 1]
                + d * (s3 - s2) * self.in_tangents[k + 1]
            )
            if self.rotation:
                out = out / np.linalg.norm(out, axis=-1, keepdims=True)
        return np.asarray(out, np.float64).reshape(*t.shape, *values.shape[1:])


def lerp(a: np.ndarray, b: np.ndarray, s: np.ndarray) -> np.ndarray:
    s = s.reshape((-1,) + (1,) * (a.ndim - 1))
    return (1.0 - s) * a + s * b


def slerp(a: np.ndarray, b: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Rows of unit quaternions a to b at s, the way the specification writes it: the angle
    between them taken from |a.b|, b's sign flipped when a.b < 0 (the shorter way); nearly equal
    ones are interpolated linearly and normalised."""
    dot = np.sum(a * b, axis=-1)
    sign = np.where(dot < 0.0, -1.0, 1.0)
    angle = np.arccos(np.clip(np.abs(dot), 0.0, 1.0))
    sin = np.sin(angle)
    close = sin < 1e-6
    safe = np.where(close, 1.0, sin)
    wa = np.where(close, 1.0 - s, np.sin(angle * (1.0 - s)) / safe)
    wb = sign * np.where(close, s, np.sin(angle * s) / safe)
    out = wa[:, None] * a + wb[:, None] * b
    return out / np.linalg.norm(out, axis=-1, keepdims=True)
