"""The output graph's imports (render/passes/output_graph.py): the target's scene attachments,
its image ("target") and, where the UI draws the target into the window (the editor's viewport),
the window's image ("window"); apart for the graph module's size."""

from __future__ import annotations

from typing import Any

from ..config import Form
from ..graph import FrameGraph
from .output_frame import OutputFrame, WindowImage


def _final_layout(vk: Any, layout: int) -> str:
    """The graph's name of a target's final layout: readback's (headless), sampled (the
    viewport's image, as its descriptor set names it) or present's."""
    if layout == vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL:
        return "TRANSFER_SRC_OPTIMAL"
    return "SHADER_READ_ONLY_OPTIMAL" if layout == vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL else "PRESENT_SRC_KHR"


class OutputImports:
    """OutputGraph's imports; the attributes they use are the graph's."""

    output: Any
    frame: OutputFrame
    _extent: tuple[int, int]

    def _import_attachments(self, graph: FrameGraph, form: Form, attachments: Any) -> None:
        """The target's SceneAttachments: depth, the HDR colour and, with MSAA, the multisampled
        one's resolve (single-sample: the multisampled colour and depth are transients); none in
        the direct form (its depth is a transient). Imported at the frame's extent where that
        is smaller (the viewport's: its picture is drawn from their corner). Every pass clears
        what it writes first and nothing after the graph reads them: their old contents go
        (UNDEFINED) and they have no final layout (UNDEFINED)."""
        if form == Form.DIRECT:
            return
        images = attachments.images
        named = [("hdr", images[-1])]
        if attachments.samples == 1:  # with MSAA depth and colour are forward's transients
            named.append(("depth", images[0]))
        width, height = self._attachments_extent()
        for name, image in named:
            size = (min(int(image.width), width), min(int(image.height), height))
            token = (id(image), image.handle, size)
            if graph.reuse_import(name, token):
                continue
            graph.import_image(
                name,
                handle=image.handle,
                view=image.view,
                format=image.format,
                extent=size,
                layout_before="UNDEFINED",
                layout_after="UNDEFINED",
                token=token,
            )

    def _attachments_extent(self) -> tuple[int, int]:
        """The extent the attachments are imported at, at most: the frame's (a camera view's
        graph: its rectangle's, render/frame/view_graph.py)."""
        return self._extent

    def _import_target(self, graph: FrameGraph, rendering: Any, extent: tuple[int, int]) -> None:
        """The target's image, imported with its format's value (FXAA's pipeline is made for it)."""
        target = self.output.target
        token = (rendering.image, rendering.view, extent, target.color_format, target.final_layout)
        if graph.reuse_import("target", token):
            return
        sampled = self.frame.window is not None  # the last frame's UI sampled it: that waits
        graph.import_image(
            "target",
            handle=rendering.image,
            view=rendering.view,
            format=target.color_format,
            extent=extent,
            layout_before="UNDEFINED",  # every pixel is written: the old contents go
            layout_after=_final_layout(self.output.vk, target.final_layout),
            stage_before="ALL_COMMANDS" if sampled else ("COLOR_ATTACHMENT_OUTPUT", "ALL_TRANSFER"),
            token=token,
        )

    def _import_window(self, graph: FrameGraph, window: WindowImage) -> None:
        """The window's image where the UI draws the target into it: as "target" is otherwise
        (after the acquire's wait and the last readback, left for present or the readback)."""
        if graph.reuse_import("window", window):
            return
        graph.import_image(
            "window",
            handle=window.image,
            view=window.view,
            format=window.format,
            extent=window.extent,
            layout_before="UNDEFINED",  # cleared
            layout_after=_final_layout(self.output.vk, window.final_layout),
            stage_before=("COLOR_ATTACHMENT_OUTPUT", "ALL_TRANSFER"),
            token=window,
        )
