"""The frame's render pass, in one of a target's three forms (FORMS):

- `hdr`: the scene in 16-bit float (HDR) colour with reverse-Z depth, then tone mapped into the
  target (sRGB swapchain image or offscreen image), then the UI on top;
- `direct`: when the output needs no HDR colour (the clamp tone map at exposure 0 without MSAA,
  render/tone_map.py's wants_hdr), the scene straight into the target, as before HDR existed: the
  HDR colour and the tone map cost the seed scenes 0.12-0.17 ms of GPU time a frame on the H100;
- `deferred`: as `hdr`, but the opaque meshes were drawn before, by the G-buffer pass
  (gpu/gbuffer.py), and lit in compute: this pass loads depth and HDR colour.

Attachments: 0 the target (written only by the tone map; in the direct form cleared and drawn
into by every subpass), 1 depth, 2 the HDR colour (multisampled with --msaa), 3 its single-sample
resolve (only with --msaa).

- subpass 0 (SUBPASS_SCENE): the meshes, from the chunk jobs' secondary command buffers (in the
  deferred form only the rows set aside: blended materials and fills of their own);
- subpass 1 (SUBPASS_BILLBOARDS): light billboards inline, depth-tested against the scene; with
  MSAA the HDR colour resolves at its end; in the direct form the overlay follows them here
  (that form has no third subpass: `output_subpass`);
- subpass 2 (SUBPASS_OUTPUT): the tone map reads the HDR colour as an input attachment (same
  pixel, no sampling) and writes the target; the overlay (ImGui) draws after it, untouched by
  exposure and tone curve.

The render passes of the forms are not compatible: a target
that changes form (`set_form`) counts up its `generation`, and whoever made pipelines against its
render pass makes them again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .attachment import attachment as _attachment
from .attachment import make_render_pass
from .gbuffer import GBuffer, create_gbuffer_pass
from .memory import Image

if TYPE_CHECKING:
    from .device import Device

SUBPASS_SCENE, SUBPASS_BILLBOARDS, SUBPASS_OUTPUT = 0, 1, 2
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


def output_subpass(form: str) -> int:
    """The subpass the overlay (and, with HDR colour, the tone map) draws in: in the direct form
    the billboards', as before HDR existed (a third subpass there would hold only the overlay,
    and a subpass boundary is a barrier)."""
    return SUBPASS_BILLBOARDS if form == "direct" else SUBPASS_OUTPUT


class TargetForm:
    """What a target (offscreen.py, swapchain.py) says of its `form`."""

    form: str

    @property
    def hdr(self) -> bool:
        """The scene is drawn in HDR colour and tone mapped (the hdr and deferred forms)."""
        return self.form != "direct"

    @property
    def output_subpass(self) -> int:
        """Where the overlay draws."""
        return output_subpass(self.form)


def _to_readback(vk: Any, last: int = SUBPASS_OUTPUT) -> Any:
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
        _attachment(vk, color_format, 1, dont_load, store, final_layout),  # every pixel written by the tone map
        _attachment(
            vk,
            getattr(vk, DEPTH_FORMAT_NAME),
            samples,
            load,
            dont_store,
            depth_layout,
            vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL if deferred else 0,
        ),
        _attachment(
            vk,
            hdr_format,
            samples,
            load,
            dont_store,
            read_layout if not msaa else color_layout,
            vk.VK_IMAGE_LAYOUT_GENERAL if deferred else 0,
        ),
    ]
    if msaa:
        attachments.append(_attachment(vk, hdr_format, 1, dont_load, dont_store, read_layout))
    ref = vk.VkAttachmentReference
    hdr = ref(attachment=2, layout=color_layout)
    depth = ref(attachment=1, layout=depth_layout)
    resolve = [ref(attachment=3, layout=color_layout)] if msaa else None
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
        vk.VkSubpassDescription(
            pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS,
            pInputAttachments=[ref(attachment=3 if msaa else 2, layout=read_layout)],
            pColorAttachments=[ref(attachment=0, layout=color_layout)],
        ),
    ]
    color_stage = vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
    fragment = vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT
    depth_stages = vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
    color_rw = vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT
    depth_rw = vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT
    compute = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT if deferred else 0
    shader_write = vk.VK_ACCESS_SHADER_WRITE_BIT if deferred else 0
    dependencies = [
        # the previous frame's use of the shared attachments (its tone map read the HDR colour),
        # or the presentation engine, before this frame clears and writes them; deferred: this
        # frame's lighting wrote the HDR colour (the G-buffer pass's own dependencies order the rest)
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=SUBPASS_SCENE,
            srcStageMask=color_stage | depth_stages | fragment | compute,
            dstStageMask=color_stage | depth_stages,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT
            | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
            | shader_write,
            dstAccessMask=color_rw | depth_rw,
        ),
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=SUBPASS_OUTPUT,
            srcStageMask=color_stage,
            dstStageMask=color_stage,
            srcAccessMask=0,
            dstAccessMask=color_rw,
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
        # the HDR colour (or its resolve) -> the tone map's input attachment read, pixel for pixel
        vk.VkSubpassDependency(
            srcSubpass=SUBPASS_BILLBOARDS,
            dstSubpass=SUBPASS_OUTPUT,
            srcStageMask=color_stage,
            dstStageMask=fragment,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_INPUT_ATTACHMENT_READ_BIT,
            dependencyFlags=vk.VK_DEPENDENCY_BY_REGION_BIT,
        ),
        _to_readback(vk),
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
    attachments in render-pass order; `input_view` is what the tone map reads."""

    def __init__(
        self,
        device: Device,
        width: int,
        height: int,
        samples: int = 1,
        form: str = "hdr",
        gbuffer_pass: Any = None,
    ) -> None:
        vk = device.vk
        self.samples = samples
        self.images: list[Image] = []
        self.gbuffer: GBuffer | None = None
        deferred = form == "deferred"
        try:
            self.images.append(
                Image(
                    device,
                    width,
                    height,
                    getattr(vk, DEPTH_FORMAT_NAME),
                    vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | (vk.VK_IMAGE_USAGE_SAMPLED_BIT if deferred else 0),
                    vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                    samples,
                )
            )
            if form == "direct":
                return
            color = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT
            hdr_usage = color | (vk.VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT if samples > 1 else 0)
            if samples == 1:
                hdr_usage |= vk.VK_IMAGE_USAGE_INPUT_ATTACHMENT_BIT
            if deferred:
                hdr_usage |= vk.VK_IMAGE_USAGE_STORAGE_BIT
            hdr_format = getattr(vk, HDR_FORMAT_NAME)
            aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT
            self.images.append(Image(device, width, height, hdr_format, hdr_usage, aspect, samples))
            if samples > 1:
                resolve_usage = color | vk.VK_IMAGE_USAGE_INPUT_ATTACHMENT_BIT
                self.images.append(Image(device, width, height, hdr_format, resolve_usage, aspect))
            if deferred:
                self.gbuffer = GBuffer(device, gbuffer_pass, self.images[0].view, self.images[1].view, width, height)
        except BaseException:
            self.destroy()
            raise

    @property
    def depth_view(self) -> Any:
        return self.images[0].view

    @property
    def input_view(self) -> Any:
        return self.images[-1].view if len(self.images) > 1 else None

    def views(self, target_view: Any) -> list[Any]:
        return [target_view] + [image.view for image in self.images]

    def destroy(self) -> None:
        if self.gbuffer is not None:
            self.gbuffer.destroy()
            self.gbuffer = None
        for image in self.images:
            image.destroy()
        self.images = []


def create_target_passes(device: Device, color_format: int, final_layout: int, samples: int, form: str) -> Any:
    """(the render pass, the G-buffer pass or None) of a target's form; on failure nothing is left made."""
    vk = device.vk
    render_pass = create_render_pass(device, color_format, final_layout, samples, form)
    if form != "deferred":
        return render_pass, None
    try:
        return render_pass, create_gbuffer_pass(device, getattr(vk, DEPTH_FORMAT_NAME), getattr(vk, HDR_FORMAT_NAME))
    except BaseException:
        vk.vkDestroyRenderPass(device.handle, render_pass, None)
        raise
