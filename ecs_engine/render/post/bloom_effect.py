"""Bloom as one post effect of the output passes (render/frame/output_passes.py: `OutputPasses.post`,
callables `post(cb, inputs)` run between the scene's render pass and the tone map), for as
long as the renderer is not yet one frame graph: the effect keeps a small graph of its own with
the HDR image imported, so its passes, barriers and chain are the same ones `add_bloom` adds to
the renderer's graph later. It registers itself as the post effect "bloom" (registry.py), of
the hdr stage.

The seam hands over the frame's PostInputs (post/inputs.py); bloom reads its single-sample HDR
colour (a gpu/memory.py Image: handle, view, format, width, height; sampled and storage usage)
in SHADER_READ_ONLY_OPTIMAL and gives it back so, its writes visible to the tone map's fragment
shader: the import's layouts before and after say that, and the graph's last barrier (to
ALL_COMMANDS) makes the composite's writes visible.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ...gpu.functions import handle_int
from ...gpu.owned import Owned
from ..graph import FrameGraph
from ..graph.resources import format_name
from .bloom import add_bloom
from .bloom_pipelines import BloomPipelines
from .bloom_settings import BloomSettings
from .inputs import PostInputs
from .registry import PostEffectKind, register

_READ = "SHADER_READ_ONLY_OPTIMAL"


class BloomEffect:
    """`effect(cb, inputs)` records the bloom over `inputs.hdr`; the graph is made again when
    the image's size changes (the chain's depth follows it), compiled again only then."""

    def __init__(self, device: Any, settings: BloomSettings | None = None) -> None:
        self.device = device
        self.settings = settings if settings is not None else BloomSettings()
        # the pipelines (shared: released, destroyed by their last user), kept across the graphs
        # made; the graph, made again with the extent (released from here and the new one added)
        self.owned = Owned(device)
        self.pipelines = BloomPipelines(device).acquire()
        self.owned.add(self.pipelines, self.pipelines.release)
        self.graph: FrameGraph | None = None
        self.extent: tuple[int, int] | None = None
        self._images: dict[int, Any] = {}  # HDR view handle value -> the image it was seen on

    def __call__(self, cb: Any, inputs: PostInputs) -> None:
        hdr_image = inputs.hdr
        extent = inputs.extent
        if self.graph is None or extent != self.extent:
            self._remake(extent)
        graph = self.graph
        assert graph is not None
        if not graph.passes:  # zero intensity: nothing to record
            return
        self._note(hdr_image)
        graph.import_image(
            "hdr",
            handle=hdr_image.handle,
            view=hdr_image.view,
            format=format_name(self.device.vk, hdr_image.format),
            extent=extent,
            layout_before=_READ,
            layout_after=_READ,
        )
        graph.compile(extent)
        graph.execute(cb)

    def _note(self, hdr_image: Any) -> None:
        """The descriptor sets are kept per view handle value: a new HDR image of the same size
        (the target made again) may come with a destroyed one's value, so its sets go then."""
        view = handle_int(self.device.vk, hdr_image.view)
        seen = self._images.get(view)
        if seen is not None and seen is not hdr_image:
            self.device.wait_idle()  # frames in flight may bind the old sets
            self.pipelines.forget_views()
            self._images.clear()
        if len(self._images) >= 16:  # images come and go (swapchain remakes): keep the recent
            self._images.clear()
        self._images[view] = hdr_image

    def _remake(self, extent: tuple[int, int]) -> None:
        if self.graph is not None:
            self.owned.release(self.graph)  # waits for the frames in flight that use its chain
        self.graph = None
        graph = FrameGraph(self.device)
        try:
            add_bloom(graph, self.settings, extent, pipelines=self.pipelines)
            graph.output("hdr")
        except BaseException:
            graph.destroy()
            raise
        self.graph, self.extent = self.owned.add(graph), extent

    def key(self, inputs: PostInputs | None = None) -> Hashable:
        """What a recorded frame's bloom depends on besides the HDR image (frame replay): the
        chain's depth follows the frame's extent."""
        return (self.settings, inputs.extent if inputs is not None else self.extent)

    def destroy(self) -> None:
        self.owned.destroy()  # the graph, then the pipelines
        self.graph = None
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
