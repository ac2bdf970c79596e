"""Bloom as one post effect of the hdr stage (registry.py's "bloom"): its passes (post/bloom.py's
add_bloom) are added to the renderer's output graph (render/passes/output_graph.py) between the
scene's rendering and the tone map, over the graph's "hdr" (the single-sample HDR colour,
sampled then written in place by the composite); the graph places every barrier and its chain
is a transient of that graph, aliased with the other effects' images.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ...gpu.owned import Owned
from ..graph import FrameGraph
from .bloom import add_bloom
from .bloom_pipelines import BloomPipelines
from .bloom_settings import BloomSettings
from .inputs import PostInputs
from .registry import PostEffectKind, register


class BloomEffect:
    """`add_hdr(graph, extent)` adds the bloom's passes over the graph's "hdr" (post/bloom.py's
    add_bloom: its chain a transient of that graph); the graph is made again when the extent
    changes (the chain's depth follows it)."""

    def __init__(self, device: Any, settings: BloomSettings | None = None) -> None:
        self.device = device
        self.settings = settings if settings is not None else BloomSettings()
        # the pipelines (shared: released, destroyed by their last user: the graphs' passes
        # acquire them too), kept across the graphs made
        self.owned = Owned(device)
        self.pipelines = BloomPipelines(device).acquire()
        self.owned.add(self.pipelines, self.pipelines.release)

    def add_hdr(self, graph: FrameGraph, extent: tuple[int, int]) -> None:
        """The chain's passes after those added so far (none at zero intensity)."""
        add_bloom(graph, self.settings, extent, pipelines=self.pipelines)

    def begin_frame(self, inputs: PostInputs) -> None:
        """Nothing of a frame's inputs but its extent (the graph's) matters to the bloom."""

    def key(self, inputs: PostInputs | None = None) -> Hashable:
        """What a recorded frame's bloom depends on besides the HDR image (frame replay): the
        chain's depth follows the frame's extent."""
        return (self.settings, inputs.extent if inputs is not None else None)

    def destroy(self) -> None:
        self.owned.destroy()  # the pipelines (the last user's release destroys them)
        self.pipelines = None  # type: ignore[assignment]


register(
    PostEffectKind(
        "bloom",
        "hdr",
        BloomSettings,
        BloomEffect,
        "physically based bloom: bright light bleeds into its surroundings (a mip chain of the HDR colour)",
    )
)
