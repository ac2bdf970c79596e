"""Render-to-texture views (a camera with a RenderTexture: a security monitor, a minimap): the
camera's frame is drawn as the window's one camera draws, into a target of its own at the
texture's size, then copied with its mips into the texture's layer of the texture pages
(render/passes/render_texture.py's RenderTexturePass, the output graph's last pass), which the
window's views, drawn after it, sample as any texture (views.py orders them).

The view's target (`TextureTarget`) is a headless target of the window's colour format, samples
and form: the pipelines made for the window's scene and tone map draw into it unchanged (so not
the pass's own RGBA8 image: a window in BGRA would need pipelines of its own). It keeps the
window's `recreations` (a swapchain's remakes), which the output passes' caches compare: the
view's frames and the window's then share them without remaking anything."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ...gpu.memory import Image
from ...gpu.scene_attachments import SceneAttachments, TargetForm
from ..config import Form
from ..graph import FrameGraph
from ..passes.output_graph import OutputGraph
from ..passes.render_texture import RenderTexturePass


class TextureTarget(TargetForm):
    """A `width` x `height` image a texture view draws into, of `window`'s colour format,
    samples and form (see the module); left in TRANSFER_SRC for the copy into the page."""

    def __init__(self, device: Any, width: int, height: int, window: Any) -> None:
        vk = device.vk
        self.device, self.window = device, window
        self.width, self.height = int(width), int(height)
        self.samples = window.samples
        self.form = window.form
        self.color_format = window.color_format
        self.final_layout = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
        usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        self.color = Image(device, self.width, self.height, self.color_format, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT)
        self.framebuffer = self.color
        self._forms: dict[Form, SceneAttachments] = {}
        try:
            self._forms[self.form] = self._attachments_for(self.form)
        except BaseException:
            self.color.destroy()
            raise

    def fits(self, width: int, height: int, window: Any) -> bool:
        """Whether it is still the target of a view of this size in `window`."""
        same = (self.width, self.height, self.color_format, self.samples)
        return same == (width, height, window.color_format, window.samples) and window is self.window

    @property
    def recreations(self) -> int:
        return int(getattr(self.window, "recreations", 0))

    def _attachments_for(self, form: Form) -> SceneAttachments:
        return SceneAttachments(self.device, self.width, self.height, self.samples, form)

    def take_readback(self) -> bool:
        return False  # the copy into the page is its frame's output

    def output_image(self, output: Any) -> tuple[Any, Any]:
        return output.handle, output.view

    def destroy(self) -> None:
        self._release_forms()
        self.color.destroy()


class TextureGraph(OutputGraph):
    """The output graphs of one texture view: the window's, with its ldr `effects` (FXAA: the
    tone map writes an image of its own, the last effect the view's whole target), and the
    copy into texture `handle`'s layer last instead of a readback."""

    def __init__(self, output: Any, pages: Any, handle: int, name: str, effects: list[Any]) -> None:
        super().__init__(output, effects)
        self.pages, self.handle, self.name = pages, int(handle), name

    def _make(self, form: Form, samples: int, color_format: int, ray: bool, oit: bool, post: Any) -> FrameGraph:
        graph = super()._make(form, samples, color_format, ray, oit, post)
        try:
            graph.remove_pass("imgui").destroy()  # the window's overlay is drawn over the window alone
            graph.add_pass(_TextureCopy(self.pages, self.handle, self.name))
        except BaseException:
            graph.destroy()
            raise
        return graph

    def _place_readback(self, graph: FrameGraph, wanted: bool) -> None:
        super()._place_readback(graph, False)


class _TextureCopy(RenderTexturePass):
    """RenderTexturePass keyed by its texture's name too (frame replay: a slot that drew another
    texture's view records anew)."""

    def __init__(self, pages: Any, handle: int, texture: str) -> None:
        super().__init__(pages, handle, source="target")
        self.texture = texture

    def key(self) -> Hashable:
        return (self.texture, super().key())
