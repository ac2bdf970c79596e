"""Where a sound is heard from, for every spatial source at once (NumPy over whole columns).

The laws are OpenAL 1.1's (its specification, section 3.4), which the tests check against a
reference written from that text:

- **distance attenuation**, clamped between the source's minimum (OpenAL's reference) distance
  and its maximum distance, by one of three models: `INVERSE` ref / (ref + rolloff (d - ref)),
  `LINEAR` 1 - rolloff (d - ref) / (max - ref) (not below 0), `EXPONENTIAL` (d / ref)^-rolloff;
- **the cone**: full gain within half the inner angle of the source's forward axis, the outer
  gain beyond half the outer angle, linear between;
- **Doppler**: f' = f (c - D v_listener) / (c - D v_source), both speeds along the line from
  the source to the listener and clamped below c / D, with c the speed of sound and D the
  Doppler factor;
- **equal-power stereo panning** (OpenAL leaves panning to the implementation): the source's
  direction in the listener's frame gives pan p = its component along the listener's right, and
  the channels take cos and sin of (p + 1) pi / 4, so the power (L^2 + R^2) is the same anywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..components.audio import EXPONENTIAL, INVERSE, LINEAR

MODELS = {"inverse": INVERSE, "linear": LINEAR, "exponential": EXPONENTIAL}
SPEED_OF_SOUND = 343.3  # m/s, OpenAL's default


@dataclass(frozen=True)
class Listener:
    """The ear: its world position, its right and forward axes (unit vectors) and its velocity."""

    position: np.ndarray
    right: np.ndarray
    forward: np.ndarray
    velocity: np.ndarray

    @staticmethod
    def at_origin() -> Listener:
        zero = np.zeros(3)
        return Listener(zero, np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -1.0]), zero)


def attenuation(
    distance: np.ndarray, model: np.ndarray, near: np.ndarray, far: np.ndarray, rolloff: np.ndarray
) -> np.ndarray:
    """The distance gain of each source (see the module), for arrays of one length."""
    d = np.clip(distance, near, np.maximum(far, near))
    inverse = near / (near + rolloff * (d - near))
    span = np.where(far > near, far - near, 1.0)
    linear = np.clip(1.0 - rolloff * (d - near) / span, 0.0, 1.0)
    with np.errstate(divide="ignore", over="ignore"):
        exponential = (d / near) ** -rolloff
    return np.where(model == LINEAR, linear, np.where(model == EXPONENTIAL, exponential, inverse))


def cone_gain(cosine: np.ndarray, inner_deg: np.ndarray, outer_deg: np.ndarray, outer_gain: np.ndarray) -> np.ndarray:
    """The cone's gain for the cosine of the angle between the source's forward axis and the
    line to the listener (see the module; angles are full cone angles in degrees)."""
    angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
    inner, outer = inner_deg / 2.0, np.maximum(outer_deg, inner_deg) / 2.0
    span = np.where(outer > inner, outer - inner, 1.0)
    t = np.clip((angle - inner) / span, 0.0, 1.0)
    return np.where(angle <= inner, 1.0, 1.0 + t * (outer_gain - 1.0))


def pan_gains(pan: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equal-power left and right gains for pan -1 (left) .. 1 (right)."""
    angle = (np.clip(pan, -1.0, 1.0) + 1.0) * (np.pi / 4.0)
    return np.cos(angle), np.sin(angle)


def doppler(
    to_listener: np.ndarray,
    distance: np.ndarray,
    source_velocity: np.ndarray,
    listener_velocity: np.ndarray,
    factor: float,
) -> np.ndarray:
    """The pitch factor of each source (see the module); 1 where the source is at the listener."""
    if factor <= 0.0:
        return np.ones(len(distance))
    safe = np.where(distance > 0.0, distance, 1.0)[:, None]
    unit = to_listener / safe
    limit = SPEED_OF_SOUND / factor
    v_source = np.minimum(np.einsum("ij,ij->i", unit, source_velocity), limit * 0.999)
    v_listener = np.minimum(unit @ listener_velocity, limit * 0.999)
    ratio = (SPEED_OF_SOUND - factor * v_listener) / (SPEED_OF_SOUND - factor * v_source)
    return np.where(distance > 0.0, np.maximum(ratio, 0.0), 1.0)


@dataclass
class SourceColumns:
    """The spatial sources of one frame, as arrays of one length (N rows)."""

    position: np.ndarray  # (N, 3) world positions
    forward: np.ndarray  # (N, 3) unit forward axes (the cone's)
    velocity: np.ndarray  # (N, 3)
    model: np.ndarray
    near: np.ndarray
    far: np.ndarray
    rolloff: np.ndarray
    cone_inner: np.ndarray
    cone_outer: np.ndarray
    cone_outer_gain: np.ndarray


def heard_points(
    listener: Listener,
    positions: np.ndarray,
    volume: np.ndarray | float,
    near: np.ndarray | float,
    far: np.ndarray | float,
    doppler_factor: float,
) -> tuple[np.ndarray, ...]:
    """(left gain, right gain, pitch factor) of one-shots played at `positions` ((N, 3)) with
    `volume`: heard by inverse distance between `near` and `far`, with no cone, still (when
    Audio.play starts one, and each frame after as the listener moves: AudioSystem)."""
    n = len(positions)
    ones, zeros = np.ones(n), np.zeros((n, 3))
    full = np.full(n, 360.0)
    sources = SourceColumns(
        positions, zeros, zeros, np.full(n, INVERSE), ones * near, ones * far, ones, full, full, ones * 0
    )
    left, right, factor = spatialize(listener, sources, doppler_factor)
    return volume * left, volume * right, factor


def spatialize(listener: Listener, sources: SourceColumns, doppler_factor: float = 1.0) -> tuple[np.ndarray, ...]:
    """(left gain, right gain, pitch factor) of each source heard by `listener`: attenuation,
    cone and panning in the gains, Doppler in the factor."""
    to_listener = listener.position[None, :] - sources.position
    distance = np.sqrt(np.einsum("ij,ij->i", to_listener, to_listener))
    gain = attenuation(distance, sources.model, sources.near, sources.far, sources.rolloff)
    safe = np.where(distance > 0.0, distance, 1.0)
    cosine = np.where(distance > 0.0, np.einsum("ij,ij->i", sources.forward, to_listener) / safe, 1.0)
    gain = gain * cone_gain(cosine, sources.cone_inner, sources.cone_outer, sources.cone_outer_gain)
    pan = np.where(distance > 0.0, (-to_listener @ listener.right) / safe, 0.0)
    left, right = pan_gains(pan)
    factor = doppler(to_listener, distance, sources.velocity, listener.velocity, doppler_factor)
    return gain * left, gain * right, factor
