"""The editor's viewport as a render target (a camera with a target): the scene is drawn
into an image of its own at exactly the Scene window's pixel size, which the UI then draws as
one of its images (render/ui/imgui_pass.py `register_image`), over a window the UI clears; so no
scene is shaded under the docked panels.

- `ViewportTarget` is that image: the window's colour format (the window's pipelines, the tone
  map, FXAA and the UI's, draw into it unchanged, as texture_views.py's TextureTarget), made at
  the window's size (its capacity) and drawn each frame from its corner at the Scene window's
  size. Everything else is the window target's: its form, samples, scene attachments (drawn
  from their corner too, as a split screen's views are), `recreations`, readback. It is made
  again only when the window target changes (a resize, which waits for the device anyway).
- One frame, one graph: the window's output graph draws "target" = this image, and its UI pass
  samples it and draws the window's image ("window": output_frame.py's WindowImage), which the
  readback reads and present shows. The graph's extent is the Scene window's size.
- `EditorViewport` is what the editor sets (`size`: pixels, or None: the Scene window is closed,
  undocked to nothing, or not built yet: the renderer draws the whole window as without an
  editor); `Renderer.render` draws through `draw` while it has a size and a UI.
"""

from __future__ import annotations

from typing import Any

from ...gpu.array_image import nearest_sampler
from ...gpu.memory import Image
from ...gpu.owned import Owned
from ...gpu.scene_attachments import Form, SceneAttachments, TargetForm
from ..passes.output_frame import WindowImage
from .draw_frame import FrameRequest


class ViewportTarget(TargetForm):
    """The viewport's colour image at the window target's size, of its format; the rest is the
    window target's (see the module). Left in SHADER_READ_ONLY, as the UI's set names it."""

    def __init__(self, device: Any, window: Any) -> None:
        vk = device.vk
        self.device, self.window = device, window
        self.width, self.height = int(window.width), int(window.height)
        self.color_format = window.color_format
        self.samples = window.samples
        self._recreations = int(getattr(window, "recreations", 0))
        self.final_layout = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
        usage |= vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        self.color = Image(device, self.width, self.height, self.color_format, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT)
        self.framebuffer = self.color
        self.window_image: WindowImage | None = None  # this frame's (set while it draws)

    def fits(self, window: Any) -> bool:
        """Whether it is still the viewport of `window` (else made again)."""
        same = (self.width, self.height, self.color_format, self.samples, self._recreations)
        now = (int(window.width), int(window.height), window.color_format, window.samples)
        return window is self.window and same == (*now, int(getattr(window, "recreations", 0)))

    # the window target's own, delegated
    @property
    def form(self) -> Form:
        return Form(self.window.form)

    @form.setter
    def form(self, form: Form) -> None:
        self.window.form = form

    @property
    def _forms(self) -> dict[Form, SceneAttachments]:
        return self.window._forms

    @_forms.setter
    def _forms(self, forms: dict[Form, SceneAttachments]) -> None:
        raise AttributeError("the window target's forms are its own")

    def set_form(self, form: Form | str) -> None:
        self.window.set_form(form)

    @property
    def attachments(self) -> SceneAttachments:
        return self.window.attachments

    @property
    def recreations(self) -> int:
        return int(getattr(self.window, "recreations", 0))

    def take_readback(self) -> bool:
        return bool(self.window.take_readback())

    def record_copy(self, cb: Any, image: Any, extent: tuple[int, int]) -> None:
        self.window.record_copy(cb, image, extent)

    def output_image(self, output: Any) -> tuple[Any, Any]:
        return output.handle, output.view

    def destroy(self) -> None:
        self.color.destroy()  # the attachments are the window's


class EditorViewport:
    """The Scene window's part of the renderer (see the module): `size` in pixels, set by the
    editor each UI build; `texture(ui)` the ImGui texture id that shows the image."""

    def __init__(self, device: Any) -> None:
        self.device = device
        self.size: tuple[int, int] | None = None
        self.target: ViewportTarget | None = None
        self.remade = 0  # targets made (the tests count them)
        self._sampler: Any = None
        self._owned: Owned | None = None  # the sampler's scope
        self._ui: Any = None  # the ImGuiRenderer the image is registered with, and its id
        self._tex_id: int | None = None

    def ensure(self, window: Any) -> ViewportTarget:
        """The viewport target of `window`, made again (after the device is idle: frames in
        flight draw the old one) when the window target changed; the UI's id kept."""
        target = self.target
        if target is not None and target.fits(window):
            return target
        if target is not None:
            self.device.wait_idle()
            target.destroy()
            self.target = None
        target = self.target = ViewportTarget(self.device, window)
        self.remade += 1
        if self._tex_id is not None:
            self._ui.update_image(self._tex_id, target.color.view, self._nearest(), target.final_layout)
        return target

    def _nearest(self) -> Any:
        if self._sampler is None:  # at 1:1 a nearest sampler copies each texel to its pixel
            device = self.device
            owned = self._owned = self._owned or Owned(device)
            sampler = nearest_sampler(device)
            self._sampler = owned.add(sampler, lambda: device.vk.vkDestroySampler(device.handle, sampler, None))
        return self._sampler

    def texture(self, ui: Any, window: Any) -> tuple[int, tuple[float, float]]:
        """The ImGui texture id of the image (registered with `ui` once) and the image's size
        (its capacity: the uv of a w x h picture is (w / W, h / H))."""
        target = self.ensure(window)
        if self._tex_id is None or self._ui is not ui:
            if self._tex_id is not None:
                self._ui.unregister_image(self._tex_id)
            self._ui = ui
            self._tex_id = ui.register_image(target.color.view, self._nearest(), target.final_layout)
        return self._tex_id, (float(target.width), float(target.height))

    def area(self, window: Any) -> tuple[int, int] | None:
        """This frame's picture size (within the window's), or None: the whole window."""
        if self.size is None:
            return None
        w, h = min(int(self.size[0]), int(window.width)), min(int(self.size[1]), int(window.height))
        return (w, h) if w > 0 and h > 0 else None

    def draw(self, r: Any, request: FrameRequest) -> Any:
        """Renderer `r`'s frame of `request` with the scene into the viewport image at `size`
        and the UI into the window (see the module)."""
        framebuffer = request.framebuffer
        window = r.target
        size = self.area(window)
        assert size is not None
        target = self.ensure(window)
        image, view = window.output_image(framebuffer if framebuffer is not None else window.framebuffer)
        whole = request.extent or (window.width, window.height)
        target.window_image = WindowImage(image, view, window.color_format, tuple(whole), window.final_layout)
        output = r.output
        r.target = output.target = target
        try:
            # the target's own image when the caller named none (its form may change here, as
            # render's own path does), else named: the form asked stays for this frame
            drawn = request._replace(framebuffer=None if framebuffer is None else target.color, extent=size)
            return r.draw_scene(drawn)
        finally:
            r.target = output.target = window
            target.window_image = None

    def destroy(self) -> None:
        """After the device is idle (the renderer's destroy waits)."""
        if self.target is not None:
            self.target.destroy()
            self.target = None
        if self._owned is not None:
            self._owned.destroy()
            self._owned = self._sampler = None
