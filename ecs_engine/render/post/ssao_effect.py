"""SSAO (GTAO, ssao.py) as the post effect "ssao" (registry.py) of the hdr stage: from the scene's
depth and the camera's projection (the seam's PostInputs, post/inputs.py) it computes "ao" and
multiplies the HDR colour by it before bloom and the tone map: ssao.py's documented fallback
until the lit shaders read "ao" themselves (it darkens direct light in creases too).

As bloom does (bloom_effect.py), it keeps a small frame graph of its own with the seam's images
imported: "depth" (D32_SFLOAT, single-sample, SHADER_READ_ONLY_OPTIMAL after the scene's render
pass, gpu/scene_attachments.py) and "hdr" (SHADER_READ_ONLY_OPTIMAL, written in place by the
composite, GENERAL in between); the graph's barriers take them there and back. The graph is
made again when the extent changes; the passes' descriptor sets follow the imported views.
Refused with MSAA (config.py): the passes sample a single-sample depth, and resolving a
multisampled depth would need a resolve pass of its own (the render pass's depth resolve is
VK_KHR_depth_stencil_resolve's, on render passes 2 or dynamic rendering, neither used here yet).
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ..graph import FrameGraph
from ..graph.resources import format_name
from .inputs import PostInputs
from .registry import PostEffectKind, register
from .ssao import add_ssao
from .ssao_settings import SsaoSettings, SsaoView

_READ = "SHADER_READ_ONLY_OPTIMAL"


class SsaoEffect:
    """`effect(cb, inputs)` records GTAO over `inputs.depth` and the composite into `inputs.hdr`."""

    def __init__(self, device: Any, settings: SsaoSettings | None = None) -> None:
        self.device = device
        self.settings = settings if settings is not None else SsaoSettings()
        self.view = SsaoView()  # its projection set from each frame's inputs
        self.graph: FrameGraph | None = None
        self.extent: tuple[int, int] | None = None
        self._images: tuple[Any, Any] = (None, None)  # (depth, hdr) the graph was made for

    def __call__(self, cb: Any, inputs: PostInputs) -> None:
        if inputs.depth is None:  # MSAA: config.py refuses ssao there; a caller that skipped it
            raise RuntimeError("SSAO needs the scene's single-sample depth (refused with MSAA)")
        if self.settings.intensity == 0:  # AO^0 = 1: nothing to record
            return
        images = (inputs.depth, inputs.hdr)
        if self.graph is None or inputs.extent != self.extent or images != self._images:
            # new images (the target made again) may reuse a destroyed view's handle value, which
            # the passes' descriptor sets are kept by: a new graph makes new sets
            self._remake(inputs.extent)
            self._images = images
        graph = self.graph
        assert graph is not None
        self.view.projection = inputs.projection
        for name, image in (("depth", inputs.depth), ("hdr", inputs.hdr)):
            graph.import_image(
                name,
                handle=image.handle,
                view=image.view,
                format=format_name(self.device.vk, image.format),
                extent=inputs.extent,
                layout_before=_READ,
                layout_after=_READ,
            )
        graph.compile(inputs.extent)
        graph.execute(cb)

    def _remake(self, extent: tuple[int, int]) -> None:
        if self.graph is not None:
            self.graph.destroy()  # waits for the frames in flight that use its transients
        self.graph = None
        graph = FrameGraph(self.device)
        try:
            add_ssao(graph, self.settings, depth="depth", out="ao", composite="hdr", view=self.view)
            graph.output("hdr")
        except BaseException:
            graph.destroy()
            raise
        self.graph, self.extent = graph, extent

    def key(self, inputs: PostInputs | None = None) -> Hashable:
        """What a recorded frame's SSAO depends on besides its images (frame replay): the
        settings, the extent and the projection (the passes' push constants: SsaoView.key)."""
        if inputs is None:
            return (self.settings, None)
        return (self.settings, inputs.extent, inputs.projection_key())

    def destroy(self) -> None:
        if self.graph is not None:
            self.graph.destroy()
            self.graph = None


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
