"""The master bus's peak limiter: the last step of every block, so that a crowded mix (a dozen
explosions at once) reaches the sound device at most at the ceiling instead of being clipped
there, which sounds like crackling.

Zero latency, instant attack, exponential release: at each output frame the gain recovers
towards 1 by the release's coefficient, then drops to ceiling / peak if the frame's louder
channel would pass the ceiling at that gain. No frame leaves above the ceiling, and both
channels share one gain, so the stereo image stays. A mix that never reaches the ceiling
passes bit for bit (a gain of exactly 1). A limiter with look-ahead would smooth the attack
further but delays every sound by its window; a game's sound answers input, so none is used.

The gain is the mixer thread's state from block to block (`Limiter.gain`); `deepest` is the
lowest gain since the Perf line last took it (`take_deepest`)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: The limiter's settings until a game sets its own (Audio.limit): the ceiling in dB of full
#: scale, and seconds for the gain to come back within 1/e.
CEILING_DB, RELEASE_S = 0.0, 0.1


@njit(nogil=True, cache=True)
def limit_block(planes, ceiling, recover, gain):  # pragma: no cover (compiled)
    """Limit `planes` ((2, frames) float32) in place from `gain`; returns the gain after the
    block and its lowest value in it. `recover`: the share of the way back to 1 made per frame."""
    g = gain
    lowest = 1.0
    for i in range(planes.shape[1]):
        peak = max(abs(planes[0, i]), abs(planes[1, i]))
        g += (1.0 - g) * recover
        if peak * g > ceiling:
            g = ceiling / peak
        if g < 1.0:
            planes[0, i] *= g
            planes[1, i] *= g
            if g < lowest:
                lowest = g
    return g, lowest


class Limiter:
    """The limiter's settings and state, on the mixer's thread."""

    def __init__(self, sample_rate: int, ceiling_db: float = CEILING_DB, release: float = RELEASE_S) -> None:
        self.sample_rate = sample_rate
        self.ceiling = self.recover = 0.0
        self.set(ceiling_db, release)
        self.gain = 1.0
        self.deepest = 1.0

    def set(self, ceiling_db: float, release: float) -> None:
        self.ceiling = 10.0 ** (ceiling_db / 20.0)
        # back within 1/e of full gain after `release` seconds
        self.recover = 1.0 - math.exp(-1.0 / (release * self.sample_rate))

    def process(self, planes: np.ndarray) -> None:
        self.gain, lowest = limit_block(planes, self.ceiling, self.recover, self.gain)
        self.deepest = min(self.deepest, lowest)

    def take_deepest(self) -> float:
        """The lowest gain since the last call (from another thread: a block's value may be
        missed, never made up)."""
        deepest, self.deepest = self.deepest, 1.0
        return deepest


def check_settings(ceiling_db: float, release: float) -> str | None:
    """What is wrong with limiter settings, in a line, or None."""
    if not isinstance(ceiling_db, (int, float)) or not math.isfinite(ceiling_db) or not -60.0 <= ceiling_db <= 0.0:
        return f"the limiter's ceiling must be from -60 to 0 dB (of full scale), got {ceiling_db!r}"
    if not isinstance(release, (int, float)) or not math.isfinite(release) or not 0.001 <= release <= 10.0:
        return f"the limiter's release must be from 0.001 to 10 seconds, got {release!r}"
    return None
