"""The bloom's settings and the arithmetic done on the CPU for it (render/post/bloom.py has the
passes; the formulas and why are told there): the chain's mip sizes and the blend weights."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import Any

from ...errors import UsageError

CHAIN_FORMAT = "VK_FORMAT_R16G16B16A16_SFLOAT"


class BloomComposite(Enum):
    ENERGY_CONSERVING = "energy_conserving"  # hdr * (1 - c) + bloom * c: light moved, not made
    ADDITIVE = "additive"  # hdr + bloom * c: brighter; for a thresholded, stylised bloom


@dataclass(frozen=True)
class BloomSettings:
    """Bevy's `Bloom::NATURAL` by default. Bad values are a UsageError when made."""

    intensity: float = 0.15  # how likely light is to scatter: 0 none, 1 all of it
    low_frequency_boost: float = 0.7  # how much more of it scatters widely (the coarse mips)
    low_frequency_boost_curvature: float = 0.95  # in [0, 1): near 1, all but the finest are boosted
    high_pass_frequency: float = 1.0  # in (0, 1]: the widest scatter, as a fraction of the chain
    threshold: float = 0.0  # soft threshold on the first downsample; 0: off (physically right)
    threshold_softness: float = 0.0  # in [0, 1]: 0 a hard knee, 1 fully soft
    composite: BloomComposite = BloomComposite.ENERGY_CONSERVING
    max_mips: int = 12  # an upper bound on the chain's depth (the viewport decides below it)

    def __post_init__(self) -> None:
        if not isinstance(self.composite, BloomComposite):
            raise UsageError(f"bloom composite must be a BloomComposite, got {self.composite!r}")
        unit = self.composite is BloomComposite.ENERGY_CONSERVING
        for name, low, high, open_high in (
            ("intensity", 0.0, 1.0 if unit else math.inf, False),
            ("low_frequency_boost", 0.0, 1.0 if unit else math.inf, False),
            ("low_frequency_boost_curvature", 0.0, 1.0, True),  # 1 divides by zero
            ("threshold", 0.0, math.inf, False),
            ("threshold_softness", 0.0, 1.0, False),
        ):
            _check_number(name, getattr(self, name), low, high, open_high)
        hp = self.high_pass_frequency
        _check_number("high_pass_frequency", hp, 0.0, 1.0, False)
        if hp == 0.0:
            raise UsageError("bloom high_pass_frequency must be above 0 (it divides), got 0")
        mips = self.max_mips
        if isinstance(mips, bool) or not isinstance(mips, int) or not 1 <= mips <= 16:
            raise UsageError(f"bloom max_mips must be a whole number in [1, 16], got {mips!r}")


def _check_number(name: str, value: Any, low: float, high: float, open_high: bool) -> None:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < low or value > high or (open_high and value == high):
        bound = f"[{low:g}, {high:g}{')' if open_high else ']'}" if math.isfinite(high) else f">= {low:g}"
        raise UsageError(f"bloom {name} must be a finite number {bound}, got {value!r}")


def chain_extents(extent: tuple[int, int], settings: BloomSettings) -> list[tuple[int, int]]:
    """The chain's mip sizes for a viewport of `extent` (width, height): mip 0 is half of it,
    rounded up (the frame graph's `scale=0.5`), each next one half again, rounded down (Vulkan's
    mips), until the short side is about 4 texels or `max_mips`."""
    width, height = max(1, math.ceil(extent[0] * 0.5)), max(1, math.ceil(extent[1] * 0.5))
    count = max(1, min(settings.max_mips, int(math.log2(min(width, height))) - 1))
    return [(max(1, width >> k), max(1, height >> k)) for k in range(count)]


def blend_factor(settings: BloomSettings, mip: int, max_mip: int) -> float:
    """How much of mip `mip` (0: the finest) is blended into the level above it (Bevy's
    `compute_blend_factor`): the intensity, plus the low-frequency boost growing towards the
    coarsest mip `max_mip` along a curve, zero past the high-pass cut."""
    s = settings
    x = mip / max_mip if max_mip else 0.0
    boost = (1.0 - (1.0 - x) ** (1.0 / (1.0 - s.low_frequency_boost_curvature))) * s.low_frequency_boost
    high_pass = 1.0 - min(max((x - s.high_pass_frequency) / s.high_pass_frequency, 0.0), 1.0)
    if s.composite is BloomComposite.ENERGY_CONSERVING:
        boost *= 1.0 - s.intensity  # so that intensity + boost stays <= 1
    return (s.intensity + boost) * high_pass


def blend_weights(settings: BloomSettings, mips: int) -> list[tuple[float, float]]:
    """Per mip k, the (source, destination) weights of its upsample into the level above (mip
    k-1, or the HDR image for k = 0): (c, 1 - c) energy-conserving, (c, 1) additive."""
    weights = []
    for k in range(mips):
        c = blend_factor(settings, k, mips - 1)
        weights.append((c, 1.0 - c if settings.composite is BloomComposite.ENERGY_CONSERVING else 1.0))
    return weights


def threshold_push(settings: BloomSettings) -> tuple[float, ...]:
    t = settings.threshold
    knee = t * settings.threshold_softness
    return (t, t - knee, 2.0 * knee, 0.25 / (knee + 1e-5))
