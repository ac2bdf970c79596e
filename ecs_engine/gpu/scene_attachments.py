"""The target's forms (`Form`): which attachments the scene draws into, and with what formats;
the renderings themselves are dynamic (vkCmdBeginRendering) in passes of the output graph
(render/passes/output_graph.py), which places the barriers, so nothing here is made against a
render pass.

- `hdr`: the scene in 16-bit float (HDR) colour with reverse-Z depth; after it, the post effects
  (render/frame/output_passes.py's `post`) and the tone map into the target (sRGB swapchain image or
  offscreen image) with the UI on top: the scene never touches the target;
- `direct`: when the output needs no HDR colour (the clamp tone map at exposure 0 without MSAA,
  render/passes/tone_map.py's wants_hdr), the scene straight into the target, as before HDR existed: the
  HDR colour and the tone map cost the seed scenes 0.12-0.17 ms of GPU time a frame on the H100;
- `deferred`: as `hdr`, but the opaque meshes were drawn before, into the G-buffer
  (gpu/gbuffer.py), and lit in compute: the scene's rendering loads depth and HDR colour.

The single-sample HDR colour (the resolve with MSAA) is left in SHADER_READ_ONLY_OPTIMAL after
the scene, for the post effects and the tone map to sample. Without MSAA depth is stored too and
left in SHADER_READ_ONLY_OPTIMAL (the layout of the frame graph's Access.COMPUTE_SAMPLED), for the
post effects that read it (SSAO): the cost is the depth written out once a frame (1280 x 720 D32:
3.7 MB of bandwidth) where a tiler could have dropped it. A multisampled depth is not stored
(resolving depth is not done here: SSAO is refused with MSAA, config.py), nor the multisampled
colour (resolved at the rendering's end).

A target keeps the attachments of every form it was drawn in (SceneAttachments per form): a
change of form makes the new form's once and never waits for the device; pipelines are made for
the forms' AttachmentFormats (`scene_formats`), so those of two forms coexist.
"""

from __future__ import annotations

from enum import StrEnum
from typing import TYPE_CHECKING, Any

from .memory import Image
from .pipeline import AttachmentFormats

if TYPE_CHECKING:
    from .device import Device


class Form(StrEnum):
    """A target's forms, named here once (render/config re-exports it: this module is below the
    configuration's, which reads MSAA_COUNTS from it). A `StrEnum`: a member equals its name."""

    DIRECT = "direct"  # straight into the target
    HDR = "hdr"  # HDR colour, tone mapped
    DEFERRED = "deferred"  # HDR with the opaque meshes lit in compute first (gpu/gbuffer.py; the
    # scene's rendering then loads depth and HDR colour)


HDR_FORMAT_NAME = "VK_FORMAT_R16G16B16A16_SFLOAT"
DEPTH_FORMAT_NAME = "VK_FORMAT_D32_SFLOAT"
MSAA_COUNTS = (1, 2, 4, 8)


def supported_samples(device: Device) -> tuple[int, ...]:
    """The MSAA counts the device can render the HDR colour and depth with."""
    limits = device.limits
    mask = int(limits.framebufferColorSampleCounts) & int(limits.framebufferDepthSampleCounts)
    return tuple(n for n in MSAA_COUNTS if mask & n)


def hdr_read_usage(device: Device) -> int:
    """How the single-sample HDR colour may be read and written outside the scene's rendering:
    sampled (the tone map, fragment post effects) and, where the device can store to the format,
    as a storage image (compute post effects); the deferred lighting needs the latter anyway."""
    vk = device.vk
    props = vk.vkGetPhysicalDeviceFormatProperties(device.physical, getattr(vk, HDR_FORMAT_NAME))
    storage = int(props.optimalTilingFeatures) & vk.VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT
    return vk.VK_IMAGE_USAGE_SAMPLED_BIT | (vk.VK_IMAGE_USAGE_STORAGE_BIT if storage else 0)


def scene_formats(vk: Any, form: Form, color_format: int, samples: int) -> AttachmentFormats:
    """What the scene's pipelines and secondaries (the chunks' outside the deferred form, the
    sky's, the set-aside rows', the billboards') are made for in `form`: the target's format in
    the direct form, else the HDR colour with the target's MSAA count; depth either way."""
    color = color_format if form == Form.DIRECT else getattr(vk, HDR_FORMAT_NAME)
    key = ((color,), getattr(vk, DEPTH_FORMAT_NAME), 1 if form == Form.DIRECT else samples)
    # one object per value: the path compares what it draws into by identity first, every frame
    found = _SCENE_FORMATS.get(key)
    if found is None:
        found = _SCENE_FORMATS[key] = AttachmentFormats(*key)
    return found


_SCENE_FORMATS: dict[tuple[tuple[int, ...], int, int], AttachmentFormats] = {}


class TargetForm:
    """What a target (offscreen.py, swapchain.py) says of its `form`, of the attachments its
    scene draws into in it and of its output: `final_layout` is the target image's after the frame."""

    form: Form
    final_layout: int
    color_format: int
    samples: int
    _forms: dict[Form, SceneAttachments]

    @property
    def hdr(self) -> bool:
        """The scene is drawn in HDR colour and tone mapped (the hdr and deferred forms)."""
        return self.form != Form.DIRECT

    @property
    def attachments(self) -> SceneAttachments:
        """The current form's (made by set_form)."""
        return self._forms[self.form]

    @property
    def hdr_image(self) -> Image | None:
        """The HDR colour the post effects and the tone map read (the resolved one with MSAA);
        None without HDR."""
        return self.attachments.hdr_image

    @property
    def depth_image(self) -> Image | None:
        """The scene's single-sample depth the post effects sample (SceneAttachments.depth_image)."""
        return self.attachments.depth_image

    @property
    def hdr_view(self) -> Any:
        image = self.attachments.hdr_image
        return image.view if image is not None else None

    def formats(self, vk: Any) -> AttachmentFormats:
        """The scene's attachment formats in the current form (scene_formats)."""
        return scene_formats(vk, self.form, self.color_format, self.samples)

    def set_form(self, form: Form | str) -> None:
        """Draw the scene through HDR colour and the tone map (`hdr`), with the opaque meshes lit
        in compute first (`deferred`), or straight into the target (`direct`) from the next
        frame: the form's attachments are made the first time (if that fails, the old form
        stays), never destroyed before the target's, so no frame in flight loses its images and
        nobody waits for the device. MSAA keeps `hdr`."""
        try:
            form = Form(form)
        except ValueError:
            raise ValueError(f"unknown target form {form!r}; forms: {', '.join(Form)}") from None
        if self.samples > 1:
            form = Form.HDR
        if form not in self._forms:
            self._forms[form] = self._attachments_for(form)
        self.form = form

    def _attachments_for(self, form: Form) -> SceneAttachments:
        raise NotImplementedError

    def _release_forms(self) -> None:
        for made in self._forms.values():
            made.destroy()
        self._forms = {}

    def output_image(self, output: Any) -> tuple[Any, Any]:
        """(VkImage, VkImageView) of the target image `output` (one of the target's) names."""
        raise NotImplementedError


class SceneAttachments:
    """The attachments of one form that a target's images share: depth, HDR colour and (with
    MSAA) its resolve; in the direct form nothing (its depth is the output graph's transient); in
    the deferred form depth sampled and the HDR colour a storage image for the lighting (the
    G-buffer itself is the output graph's transient: render/passes/deferred_passes.py).
    `images` holds depth (single-sample only), then the HDR colour (single-sample: with MSAA the
    resolve; the multisampled colour and depth are the output graph's transients, which nothing
    after the scene's rendering reads); `hdr_image` is the HDR colour the post effects and the
    tone map read."""

    def __init__(
        self,
        device: Device,
        width: int,
        height: int,
        samples: int = 1,
        form: Form = Form.HDR,
    ) -> None:
        vk = device.vk
        self.samples = samples
        self.images: list[Image] = []  # depth, HDR colour, its resolve (in the order made)
        deferred = form == Form.DEFERRED
        # the deferred lighting samples depth; in the hdr form the post effects may (single-sample)
        sampled = vk.VK_IMAGE_USAGE_SAMPLED_BIT if deferred or samples == 1 else 0
        if form == Form.DIRECT:  # its depth is the output graph's transient (render/passes/forward.py)
            return
        try:
            if samples == 1:  # with MSAA depth and colour are the output graph's (forward.py)
                self.images.append(
                    Image(
                        device,
                        width,
                        height,
                        getattr(vk, DEPTH_FORMAT_NAME),
                        vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | sampled,
                        vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                    )
                )
            color = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT
            read = hdr_read_usage(device) | (vk.VK_IMAGE_USAGE_STORAGE_BIT if deferred else 0)
            hdr_format = getattr(vk, HDR_FORMAT_NAME)
            self.images.append(Image(device, width, height, hdr_format, color | read, vk.VK_IMAGE_ASPECT_COLOR_BIT))
        except BaseException:
            self.destroy()
            raise

    @property
    def depth_view(self) -> Any:
        return self.images[0].view

    @property
    def depth_image(self) -> Image | None:
        """The single-sample depth the hdr and deferred forms store, in SHADER_READ_ONLY_OPTIMAL
        after the scene (the post effects sample it); None in the direct form and with MSAA."""
        return self.images[0] if len(self.images) > 1 else None

    @property
    def hdr_image(self) -> Image | None:
        """The single-sample HDR colour (the resolve with MSAA), in SHADER_READ_ONLY_OPTIMAL after
        the scene; None in the direct form."""
        return self.images[-1] if self.images else None

    def destroy(self) -> None:
        for image in self.images:
            image.destroy()
        self.images = []
