"""The frame's scene render pass, in one of a target's three forms (FORMS):

- `hdr`: the scene in 16-bit float (HDR) colour with reverse-Z depth; after the pass, the post
  effects (render/output_passes.py's `post`) and the tone map into the target (sRGB swapchain
  image or offscreen image) with the UI on top, drawn with dynamic rendering (vkCmdBeginRendering,
  render/output_passes.py): this pass never touches the target;
- `direct`: when the output needs no HDR colour (the clamp tone map at exposure 0 without MSAA,
  render/tone_map.py's wants_hdr), the scene straight into the target, as before HDR existed: the
  HDR colour and the tone map cost the seed scenes 0.12-0.17 ms of GPU time a frame on the H100;
- `deferred`: as `hdr`, but the opaque meshes were drawn before, by the G-buffer pass
  (gpu/gbuffer.py), and lit in compute: this pass loads depth and HDR colour.

Attachments of the hdr and deferred forms: 0 the HDR colour (multisampled with --msaa), 1 depth,
2 the HDR colour's single-sample resolve (only with --msaa). The single-sample HDR colour (the
resolve with MSAA) ends the pass in SHADER_READ_ONLY_OPTIMAL, for the post effects and the tone
map to sample. Without MSAA depth is stored too and ends in SHADER_READ_ONLY_OPTIMAL (the layout
of the frame graph's Access.COMPUTE_SAMPLED), for the post effects that read it (SSAO). It is
stored whichever effects are on: the store op is baked into the render pass, and deciding it per
effect would make the target change render pass (and its pipelines) with the effects; the cost
is the depth written out once a frame (1280 x 720 D32: 3.7 MB of bandwidth) where a tiler could
have dropped it, and a layout change that may decompress depth on some GPUs. A multisampled
depth is not stored (resolving depth is not done here: SSAO is refused with MSAA, config.py).

Attachments of the direct form: 0 the target (cleared and drawn into by every subpass), 1 depth.
Attachment 0 is in both the colour the scene draws into, cleared to the background
(render/path.py's TargetState lists the clear values in this order).

- subpass 0 (SUBPASS_SCENE): the meshes, from the chunk jobs' secondary command buffers (in the
  deferred form only the rows set aside: blended materials and fills of their own);
- subpass 1 (SUBPASS_BILLBOARDS): light billboards inline, depth-tested against the scene; with
  MSAA the HDR colour resolves at its end; in the direct form the overlay follows them here
  (`TargetForm.overlay_pass`).

The render passes of the forms are not compatible: a target
that changes form (`set_form`) counts up its `generation`, and whoever made pipelines against its
render pass makes them again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .attachment import attachment as _attachment
from .attachment import make_render_pass
from .gbuffer import GBuffer
from .memory import Image

if TYPE_CHECKING:
    from .device import Device

SUBPASS_SCENE, SUBPASS_BILLBOARDS = 0, 1
#: a target's forms: straight into the target, HDR colour tone mapped, or HDR with the opaque
#: meshes lit in compute first (gpu/gbuffer.py; this pass then loads depth and HDR colour)
FORMS = ("direct", "hdr", "deferred")
HDR_FORMAT_NAME = "VK_FORMAT_R16G16B16A16_SFLOAT"
DEPTH_FORMAT_NAME = "VK_FORMAT_D32_SFLOAT"
MSAA_COUNTS = (1, 2, 4, 8)


def supported_samples(device: Device) -> tuple[int, ...]:
    """The MSAA counts the device can render the HDR colour and depth with."""
    limits = device.limits
    mask = int(limits.framebufferColorSampleCounts) & int(limits.framebufferDepthSampleCounts)
    return tuple(n for n in MSAA_COUNTS if mask & n)


def hdr_read_usage(device: Device) -> int:
    """How the single-sample HDR colour may be read and written outside the scene pass: sampled
    (the tone map, fragment post effects) and, where the device can store to the format, as a
    storage image (compute post effects); the deferred lighting needs the latter anyway."""
    vk = device.vk
    props = vk.vkGetPhysicalDeviceFormatProperties(device.physical, getattr(vk, HDR_FORMAT_NAME))
    storage = int(props.optimalTilingFeatures) & vk.VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT
    return vk.VK_IMAGE_USAGE_SAMPLED_BIT | (vk.VK_IMAGE_USAGE_STORAGE_BIT if storage else 0)


class TargetForm:
    """What a target (offscreen.py, swapchain.py) says of its `form` and of where its output is
    drawn: `render_pass` is the scene's, `final_layout` the target image's after the frame."""

    form: str
    render_pass: Any
    final_layout: int

    @property
    def hdr(self) -> bool:
        """The scene is drawn in HDR colour and tone mapped (the hdr and deferred forms)."""
        return self.form != "direct"

    @property
    def overlay_pass(self) -> tuple[Any, int]:
        """(render pass, subpass) the overlay draws in: the direct form's billboards subpass, or
        (None, 0): dynamic rendering into the target after the tone map (pipelines made for the
        target's `color_format`)."""
        return (self.render_pass, SUBPASS_BILLBOARDS) if self.form == "direct" else (None, 0)

    def output_image(self, framebuffer: Any) -> tuple[Any, Any]:
        """(VkImage, VkImageView) of the target image a framebuffer of this target is drawn for."""
        raise NotImplementedError


def _to_readback(vk: Any, last: int) -> Any:
    """The target, written in the last subpass, before whatever reads it next (a copy for
    readback, or present)."""
    return vk.VkSubpassDependency(
        srcSubpass=last,
        dstSubpass=vk.VK_SUBPASS_EXTERNAL,
        srcStageMask=vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
        dstStageMask=vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
        srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
        dstAccessMask=vk.VK_ACCESS_TRANSFER_READ_BIT,
    )


def create_render_pass(
    device: Device, color_format: int, final_layout: int, samples: int = 1, form: str = "hdr"
) -> Any:
    """The scene's render pass of a form; `color_format` and `final_layout` are the target's,
    used by the direct form alone (the others leave the target to the tone map's rendering)."""
    if form != "hdr" and samples > 1:
        raise ValueError(f"MSAA resolves the HDR colour in the forward pass: the {form} form has one sample")
    if form == "direct":
        return _create_direct_pass(device, color_format, final_layout)
    vk = device.vk
    msaa = samples > 1
    deferred = form == "deferred"

    clear, dont_load = vk.VK_ATTACHMENT_LOAD_OP_CLEAR, vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE
    store, dont_store = vk.VK_ATTACHMENT_STORE_OP_STORE, vk.VK_ATTACHMENT_STORE_OP_DONT_CARE
    color_layout = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    read_layout = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
    depth_layout = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL
    hdr_format = getattr(vk, HDR_FORMAT_NAME)
    load = vk.VK_ATTACHMENT_LOAD_OP_LOAD if deferred else clear  # deferred: what the G-buffer pass and lighting left
    attachments = [
        _attachment(  # the single-sample HDR colour is stored for the post effects and tone map
            vk,
            hdr_format,
            samples,
            load,
            dont_store if msaa else store,
            color_layout if msaa else read_layout,
            vk.VK_IMAGE_LAYOUT_GENERAL if deferred else 0,
        ),
        _attachment(  # single-sample depth is stored for the post effects that sample it (SSAO)
            vk,
            getattr(vk, DEPTH_FORMAT_NAME),
            samples,
            load,
            dont_store if msaa else store,
            depth_layout if msaa else read_layout,
            vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL if deferred else 0,
        ),
    ]
    if msaa:
        attachments.append(_attachment(vk, hdr_format, 1, dont_load, store, read_layout))
    ref = vk.VkAttachmentReference
    hdr = ref(attachment=0, layout=color_layout)
    depth = ref(attachment=1, layout=depth_layout)
    resolve = [ref(attachment=2, layout=color_layout)] if msaa else None
    subpasses = [
        vk.VkSubpassDescription(
            pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pColorAttachments=[hdr], pDepthStencilAttachment=depth
        ),
        vk.VkSubpassDescription(
            pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS,
            pColorAttachments=[hdr],
            pResolveAttachments=resolve,
            pDepthStencilAttachment=depth,
        ),
    ]
    color_stage = vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
    shaders = vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
    depth_stages = vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
    color_rw = vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT
    depth_rw = vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT
    dependencies = [
        # the previous frame's use of the shared attachments (its tone map and post effects read
        # or wrote the HDR colour in fragment or compute shaders) before this frame clears and
        # writes them; deferred: this frame's lighting wrote the HDR colour (the G-buffer pass's
        # own dependencies order the rest)
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=SUBPASS_SCENE,
            srcStageMask=color_stage | depth_stages | shaders,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT
            | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
            | vk.VK_ACCESS_SHADER_WRITE_BIT,
            dstAccessMask=color_rw | depth_rw,
        ),
        # scene -> billboards: colour blended on top, depth tested against the scene
        vk.VkSubpassDependency(
            srcSubpass=SUBPASS_SCENE,
            dstSubpass=SUBPASS_BILLBOARDS,
            srcStageMask=color_stage | depth_stages,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
            dstAccessMask=color_rw | depth_rw,
            dependencyFlags=vk.VK_DEPENDENCY_BY_REGION_BIT,
        ),
        # the HDR colour (or its resolve) and the single-sample depth, in their final layouts,
        # before the post effects and the tone map sample them (or a compute post effect writes
        # the colour)
        vk.VkSubpassDependency(
            srcSubpass=SUBPASS_BILLBOARDS,
            dstSubpass=vk.VK_SUBPASS_EXTERNAL,
            srcStageMask=color_stage | depth_stages,
            dstStageMask=shaders,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT,
        ),
    ]
    return make_render_pass(device, attachments, subpasses, dependencies)


def _create_direct_pass(device: Device, color_format: int, final_layout: int) -> Any:
    """The scene, the billboards and the overlay all drawn into the target (hdr=False)."""
    vk = device.vk
    color_layout = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    depth_layout = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL
    clear, dont_store = vk.VK_ATTACHMENT_LOAD_OP_CLEAR, vk.VK_ATTACHMENT_STORE_OP_DONT_CARE
    attachments = [
        _attachment(vk, color_format, 1, clear, vk.VK_ATTACHMENT_STORE_OP_STORE, final_layout),
        _attachment(vk, getattr(vk, DEPTH_FORMAT_NAME), 1, clear, dont_store, depth_layout),
    ]
    ref = vk.VkAttachmentReference
    color, depth = ref(attachment=0, layout=color_layout), ref(attachment=1, layout=depth_layout)
    graphics = vk.VK_PIPELINE_BIND_POINT_GRAPHICS
    subpasses = [  # the scene; the billboards, then the overlay
        vk.VkSubpassDescription(pipelineBindPoint=graphics, pColorAttachments=[color], pDepthStencilAttachment=depth),
        vk.VkSubpassDescription(pipelineBindPoint=graphics, pColorAttachments=[color], pDepthStencilAttachment=depth),
    ]
    color_stage = vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
    depth_stages = vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
    color_write = vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT
    color_rw = color_write | vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT
    depth_write = vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
    depth_rw = depth_write | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT
    by_region = vk.VK_DEPENDENCY_BY_REGION_BIT
    dependencies = [
        # the previous frame's depth (shared by the frames in flight) and the presentation
        # engine's hold on the image, before the clears
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=SUBPASS_SCENE,
            srcStageMask=color_stage | depth_stages,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=color_write | depth_write,
            dstAccessMask=color_rw | depth_rw,
        ),
        # scene -> billboards (blended on top, depth tested) and overlay (blended on top)
        vk.VkSubpassDependency(
            srcSubpass=SUBPASS_SCENE,
            dstSubpass=SUBPASS_BILLBOARDS,
            srcStageMask=color_stage | depth_stages,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=color_write | depth_write,
            dstAccessMask=color_rw | depth_rw,
            dependencyFlags=by_region,
        ),
        _to_readback(vk, SUBPASS_BILLBOARDS),
    ]
    return make_render_pass(device, attachments, subpasses, dependencies)


class SceneAttachments:
    """The attachments a target shares between its framebuffers: depth, HDR colour and (with
    MSAA) its resolve; in the direct form depth alone; in the deferred form also the G-buffer
    (gpu/gbuffer.py: its images and the first pass's framebuffer), depth sampled and the HDR
    colour a storage image for the lighting. `views(target_view)` lists a framebuffer's
    attachments in render-pass order (the target's view only in the direct form); `hdr_image` is
    the single-sample HDR colour the post effects and the tone map read."""

    def __init__(
        self,
        device: Device,
        width: int,
        height: int,
        samples: int = 1,
        form: str = "hdr",
    ) -> None:
        vk = device.vk
        self.samples = samples
        self.images: list[Image] = []  # depth, HDR colour, its resolve (in the order made)
        self.gbuffer: GBuffer | None = None
        deferred = form == "deferred"
        # the deferred lighting samples depth; in the hdr form the post effects may (single-sample)
        sampled = vk.VK_IMAGE_USAGE_SAMPLED_BIT if deferred or samples == 1 else 0
        try:
            self.images.append(
                Image(
                    device,
                    width,
                    height,
                    getattr(vk, DEPTH_FORMAT_NAME),
                    vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | (sampled if form != "direct" else 0),
                    vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                    samples,
                )
            )
            if form == "direct":
                return
            color = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT
            read = hdr_read_usage(device) | (vk.VK_IMAGE_USAGE_STORAGE_BIT if deferred else 0)
            hdr_format = getattr(vk, HDR_FORMAT_NAME)
            aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT
            if samples > 1:  # resolved at the end of the pass, never read: may stay in tile memory
                transient = color | vk.VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT
                self.images.append(Image(device, width, height, hdr_format, transient, aspect, samples))
            self.images.append(Image(device, width, height, hdr_format, color | read, aspect))
            if deferred:
                self.gbuffer = GBuffer(device, width, height)
        except BaseException:
            self.destroy()
            raise

    @property
    def depth_view(self) -> Any:
        return self.images[0].view

    @property
    def depth_image(self) -> Image | None:
        """The single-sample depth the hdr and deferred forms store, in SHADER_READ_ONLY_OPTIMAL
        after the scene pass (the post effects sample it); None in the direct form and with MSAA."""
        return self.images[0] if len(self.images) > 1 and self.samples == 1 else None

    @property
    def hdr_image(self) -> Image | None:
        """The single-sample HDR colour (the resolve with MSAA), in SHADER_READ_ONLY_OPTIMAL after
        the scene pass; None in the direct form."""
        return self.images[-1] if len(self.images) > 1 else None

    def views(self, target_view: Any) -> list[Any]:
        if len(self.images) == 1:  # direct: the target, depth
            return [target_view, self.images[0].view]
        return [self.images[1].view, self.images[0].view, *(image.view for image in self.images[2:])]

    def destroy(self) -> None:
        if self.gbuffer is not None:
            self.gbuffer.destroy()
            self.gbuffer = None
        for image in self.images:
            image.destroy()
        self.images = []
