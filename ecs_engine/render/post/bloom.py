"""Physically based bloom, as in Call of Duty: Advanced Warfare (Jimenez, "Next generation post
processing", SIGGRAPH 2014) and Bevy's bloom plugin: a post effect on the HDR colour before the
tone map, added to a frame graph with one call, `add_bloom(graph, BloomSettings(), extent)`.

Light scatters in the lens and the eye; a real camera's image is the scene convolved with a wide
point-spread function of small weight. It is built from a mip chain of the HDR image:

1. Downsample: the HDR image into mip 0 of a half-resolution R16G16B16A16_SFLOAT chain, then
   mip k-1 into mip k, each with the 13-tap filter (shaders/bloom_downsample.comp). The first
   step weights its five boxes by 1 / (1 + luma) (the Karis average, normalised) so that a single
   firefly pixel does not bloom into a square (normalised as Jimenez's: a flat field passes
   unchanged; Bevy's unnormalised weights dim it too). There is no threshold by default: all
   light scatters, the bright light simply shows it.
2. Upsample: from the smallest mip, the 3x3 tent of mip k+1 is blended into mip k
   (shaders/bloom_upsample.comp), mip_k = mip_k * (1 - c_(k+1)) + tent * c_(k+1), and last into
   the HDR image itself: hdr = mix(hdr, tent(mip 0), c_0) = hdr * (1 - c_0) + tent * c_0,
   where c_0 is the intensity itself (the low-frequency boost is 0 at the finest level).

Energy-conserving composite: every blend is a convex mix (c in [0, 1]) and every filter's
weights sum to 1, so the bloom moves light around instead of adding it: the image's sum can
only drop (up to the clamp-to-edge addressing at the borders), and by at most the fraction c_0
of it (hdr keeps (1 - c_0) of its light where it
was; the blurred part holds at most all of it, less what the Karis weights take from fireflies).
A plain addition (hdr + bloom) would brighten the whole frame with the intensity and need a
threshold to keep dark parts dark; the mix needs none. The weights c_k are Bevy's blend factors
(`blend_factor`): `intensity` at the finest level, raised towards the coarse ones by
`low_frequency_boost` (scaled by 1 - intensity so that c stays <= 1), cut above
`high_pass_frequency` of the chain.

The mip count follows the viewport: the smallest mip is about 4 texels on the short side (as
Bevy's, whose chain is 512 texels high and 8 mips deep), so a bloom spreads over the same
fraction of the screen at any resolution.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ..graph import Access, ImageDesc, Pass
from .bloom_pipelines import BloomPipelines
from .bloom_settings import (
    CHAIN_FORMAT,
    BloomComposite,
    BloomSettings,
    blend_factor,
    blend_weights,
    chain_extents,
    threshold_push,
)

__all__ = ["BloomComposite", "BloomSettings", "add_bloom", "blend_factor", "blend_weights", "chain_extents"]


class _BloomPass(Pass):
    """A step of the chain; all share one BloomPipelines."""

    def __init__(self, name: str, gpu: BloomPipelines, hdr: str, chain: str) -> None:
        self.name = name
        self.gpu = gpu.acquire()
        self.hdr, self.chain = hdr, chain
        self._released = False

    def declares(self) -> Hashable:
        return ()  # its setup reads only what it was made with

    def destroy(self) -> None:
        if not self._released:
            self._released = True
            self.gpu.release()


class BloomDownsample(_BloomPass):
    """Mip k of the chain from mip k-1, or from the HDR image for k = 0 (which creates the chain)."""

    def __init__(
        self, gpu: BloomPipelines, hdr: str, chain: str, desc: ImageDesc, mip: int, settings: BloomSettings
    ) -> None:
        super().__init__(f"bloom_downsample_{mip}", gpu, hdr, chain)
        self.desc, self.mip = desc, mip
        self.push = threshold_push(settings) if mip == 0 else (0.0, 0.0, 0.0, 0.0)

    def setup(self, builder: Any) -> None:
        if self.mip == 0:
            builder.create(self.chain, self.desc)
            builder.read(self.hdr, Access.COMPUTE_SAMPLED)
        else:
            builder.read(self.chain, Access.COMPUTE_SAMPLED, mip=self.mip - 1)
        builder.write(self.chain, Access.COMPUTE_WRITE, mip=self.mip)

    def record(self, cb: Any, ctx: Any) -> None:
        chain = ctx.image(self.chain)
        self.gpu.track(chain)
        if self.mip == 0:  # the HDR image may be larger than the view's rectangle: read only it
            hdr = ctx.image(self.hdr)
            kind, source, source_size = "first", hdr.view, hdr.extent
        else:
            kind, source, source_size = "down", chain.mip_view(self.mip - 1), chain.mip_extent(self.mip - 1)
        target, size = chain.mip_view(self.mip), chain.mip_extent(self.mip)
        self.gpu.dispatch(cb, kind, source, target, size, self.push, source_size)

    def key(self) -> Hashable:
        return (self.mip, self.push)


class BloomUpsample(_BloomPass):
    """The tent of mip k blended into mip k-1, or into the HDR image for k = 0 (the composite)."""

    def __init__(self, gpu: BloomPipelines, hdr: str, chain: str, mip: int, weights: tuple[float, float]) -> None:
        super().__init__("bloom_composite" if mip == 0 else f"bloom_upsample_{mip}", gpu, hdr, chain)
        self.mip, self.weights = mip, weights

    def setup(self, builder: Any) -> None:
        builder.read(self.chain, Access.COMPUTE_SAMPLED, mip=self.mip)
        if self.mip == 0:
            builder.write(self.hdr, Access.COMPUTE_READ_WRITE)
        else:
            builder.write(self.chain, Access.COMPUTE_READ_WRITE, mip=self.mip - 1)

    def record(self, cb: Any, ctx: Any) -> None:
        chain = ctx.image(self.chain)
        self.gpu.track(chain)
        if self.mip == 0:
            hdr = ctx.image(self.hdr)
            target, size = hdr.view, hdr.extent  # the view's rectangle, maybe a corner of the image
        else:
            target, size = chain.mip_view(self.mip - 1), chain.mip_extent(self.mip - 1)
        source = chain.mip_view(self.mip)
        self.gpu.dispatch(cb, "up", source, target, size, self.weights, chain.mip_extent(self.mip))

    def key(self) -> Hashable:
        return (self.mip, self.weights)


def bloom_passes(
    gpu: BloomPipelines, settings: BloomSettings, extent: tuple[int, int], *, hdr: str = "hdr", chain: str = "bloom"
) -> list[Pass]:
    """The chain's passes in order: N downsamples, N - 1 upsamples, the composite into `hdr`."""
    mips = len(chain_extents(extent, settings))
    desc = ImageDesc(format=CHAIN_FORMAT, scale=0.5, mips=mips)
    weights = blend_weights(settings, mips)
    passes: list[Pass] = [BloomDownsample(gpu, hdr, chain, desc, k, settings) for k in range(mips)]
    passes += [BloomUpsample(gpu, hdr, chain, k, weights[k]) for k in range(mips - 1, -1, -1)]
    return passes


def add_bloom(
    graph: Any,
    settings: BloomSettings,
    extent: tuple[int, int],
    *,
    hdr: str = "hdr",
    chain: str = "bloom",
    pipelines: BloomPipelines | None = None,
    before: str | None = None,
) -> list[Pass]:
    """Add the bloom over the graph's image `hdr` (R16G16B16A16_SFLOAT, usage SAMPLED and
    STORAGE, single-sampled: the resolved colour) for a viewport of `extent`; the passes it
    added (none at zero intensity: the composite would leave the image as it is), in order,
    each just before the pass named `before` if given (the tone map). The passes destroy the
    pipelines with the last of them (`graph.destroy()`)."""
    if settings.intensity == 0.0:  # c_0 is 0 then, whatever the boost: nothing reaches the image
        return []
    gpu = pipelines or BloomPipelines(graph.device)
    passes = bloom_passes(gpu, settings, extent, hdr=hdr, chain=chain)
    for p in passes:
        if before is None:
            graph.add_pass(p)
        else:
            graph.add_pass(p, before=before)
    return passes
