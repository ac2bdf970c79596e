"""SSAO (GTAO, ssao.py) as the post effect "ssao" (registry.py) of the hdr stage: from the scene's
depth and the camera's projection (the frame's PostInputs, post/inputs.py) it computes "ao" and
multiplies the HDR colour by it before bloom and the tone map: ssao.py's documented fallback
until the lit shaders read "ao" themselves (it darkens direct light in creases too).

Its passes (add_ssao) are added to the renderer's output graph (render/passes/output_graph.py)
between the scene's rendering and the tone map, reading the graph's "depth" (D32_SFLOAT,
single-sample, sampled) and writing "hdr" in place; "ao" and its noisy form are transients of
that graph, aliased with the other effects' images; the passes' descriptor sets follow the
graph's compiles. Refused with MSAA (config.py): the passes sample a single-sample depth.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ..graph import FrameGraph
from .inputs import PostInputs
from .registry import PostEffectKind, register
from .ssao import add_ssao
from .ssao_settings import SsaoSettings, SsaoView


class SsaoEffect:
    """`add_hdr(graph, extent)` adds GTAO over the graph's "depth" and the composite into its
    "hdr"; `begin_frame(inputs)` hands the passes the frame's projection."""

    def __init__(self, device: Any, settings: SsaoSettings | None = None) -> None:
        self.device = device
        self.settings = settings if settings is not None else SsaoSettings()
        self.view = SsaoView()  # its projection set from each frame's inputs

    def add_hdr(self, graph: FrameGraph, extent: tuple[int, int]) -> None:
        """The passes after those added so far; none at zero intensity (AO^0 = 1)."""
        if self.settings.intensity == 0:
            return
        add_ssao(graph, self.settings, depth="depth", out="ao", composite="hdr", view=self.view)

    def begin_frame(self, inputs: PostInputs) -> None:
        if inputs.depth is None:  # MSAA: config.py refuses ssao there; a caller that skipped it
            raise RuntimeError("SSAO needs the scene's single-sample depth (refused with MSAA)")
        self.view.projection = inputs.projection

    def key(self, inputs: PostInputs | None = None) -> Hashable:
        """What a recorded frame's SSAO depends on besides its images (frame replay): the
        settings, the extent and the projection (the passes' push constants: SsaoView.key)."""
        if inputs is None:
            return (self.settings, None)
        return (self.settings, inputs.extent, inputs.projection_key())

    def destroy(self) -> None:
        """Nothing of its own: its passes are the output graph's (destroyed with it)."""


register(
    PostEffectKind(
        "ssao",
        "hdr",
        SsaoSettings,
        SsaoEffect,
        "screen-space ambient occlusion (GTAO from depth): creases and contact darken, before bloom",
        depth=True,
        before=("bloom",),
    )
)
