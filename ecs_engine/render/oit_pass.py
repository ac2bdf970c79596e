"""Weighted blended order-independent transparency (issue 15; M. McGuire and L. Bavoil, "Weighted
blended order-independent transparency", JCGT 2013), the renderer's `transparency="weighted"`.

Sorting blended rows back to front (set_aside_pass.py) is per object: interleaved or
intersecting surfaces blend in the wrong order within a pixel, and the sort costs time at large
counts. Here the order does not matter: every blended fragment adds its premultiplied colour,
weighted by its alpha and its distance from the eye, to an accumulation target, and multiplies a
revealage target by (1 - alpha); a full-screen composite then draws the weighted average colour
over the scene by 1 - revealage. The result approximates the sorted blend (exact for one layer,
close for layers of similar colour, nearer layers weighing more).

It runs in the deferred form, where the opaque depth exists before the target's pass: after the
lighting dispatch, a pass of its own draws the blended rows (mesh_*_oit.frag, the "weighted"
blend, gpu/pipeline.py) into the two targets against the G-buffer's depth (read-only, no
writes); the composite (oit_composite.frag) is the last draw of the target pass's first subpass,
after the sky and the other set-aside rows.

Known limit: blended surfaces are depth-tested against the G-buffer's opaque meshes only, not
against the rows drawn forward after the lighting (mirroring, wireframe and point materials),
which the composite then draws over where a transparent surface lies behind them.
"""

from __future__ import annotations

from typing import Any

from ..gpu.array_image import clamped_sampler
from ..gpu.attachment import attachment, create_framebuffer, make_render_pass
from ..gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_images
from ..gpu.device import Device
from ..gpu.memory import Image
from ..gpu.pipeline import GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ..gpu.render_pass import DEPTH_FORMAT_NAME
from ..gpu.secondary import SecondaryBuffers
from .config import Transparency
from .path import TargetState
from .sky_pass import full_screen_secondary

ACCUMULATION_FORMAT = "VK_FORMAT_R16G16B16A16_SFLOAT"
REVEALAGE_FORMAT = "VK_FORMAT_R16_SFLOAT"
TRANSPARENCY_MODES = Transparency.names()


def create_oit_pass(device: Device) -> Any:
    """Accumulation (cleared to 0), revealage (cleared to 1), both read by the composite after
    the pass; depth loaded and kept read-only (the G-buffer's, as the lighting left it)."""
    vk = device.vk
    clear, load, store = vk.VK_ATTACHMENT_LOAD_OP_CLEAR, vk.VK_ATTACHMENT_LOAD_OP_LOAD, vk.VK_ATTACHMENT_STORE_OP_STORE
    read = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
    depth_read = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL
    attachments = [
        attachment(vk, getattr(vk, ACCUMULATION_FORMAT), 1, clear, store, read),
        attachment(vk, getattr(vk, REVEALAGE_FORMAT), 1, clear, store, read),
        attachment(vk, getattr(vk, DEPTH_FORMAT_NAME), 1, load, store, depth_read, depth_read),
    ]
    color = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    subpass = vk.VkSubpassDescription(
        pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS,
        pColorAttachments=[vk.VkAttachmentReference(attachment=k, layout=color) for k in (0, 1)],
        pDepthStencilAttachment=vk.VkAttachmentReference(attachment=2, layout=depth_read),
    )
    color_stage = vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
    fragment = vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT
    tests = vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
    dependencies = [
        # the G-buffer's depth and the lighting before the tests; last frame's composite reads
        # before this frame's clears
        vk.VkSubpassDependency(
            srcSubpass=vk.VK_SUBPASS_EXTERNAL,
            dstSubpass=0,
            srcStageMask=tests | vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | fragment,
            dstStageMask=tests | color_stage,
            srcAccessMask=vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
        ),
        # the two targets before the composite samples them
        vk.VkSubpassDependency(
            srcSubpass=0,
            dstSubpass=vk.VK_SUBPASS_EXTERNAL,
            srcStageMask=color_stage,
            dstStageMask=fragment,
            srcAccessMask=vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
            dstAccessMask=vk.VK_ACCESS_SHADER_READ_BIT,
        ),
    ]
    return make_render_pass(device, attachments, [subpass], dependencies)


class WeightedTransparency:
    """The pass, its targets (made for a target's size and depth), and the composite."""

    def __init__(self, device: Device, secondaries: SecondaryBuffers) -> None:
        self.device, self.vk, self.secondaries = device, device.vk, secondaries
        vk = self.vk
        self.render_pass = create_oit_pass(device)
        self.sampler = clamped_sampler(device, max_lod=0.0)
        sampler = vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
        self.set_layout = DescriptorSetLayout(device, [(b, sampler, vk.VK_SHADER_STAGE_FRAGMENT_BIT) for b in (0, 1)])
        self.pool = DescriptorPool(device, 1, {sampler: 2})
        self.descriptor_set = self.pool.allocate(self.set_layout)
        self.set_array = vk.ffi.new("VkDescriptorSet[1]", [self.descriptor_set])
        self.layout = pipeline_layout(device, [self.set_layout.handle])
        self.composite: Any = None  # made against the target's pass on first use
        self._composite_pass: Any = None
        self.images: list[Image] = []
        self.framebuffer: Any = None
        self._made_for: tuple[Any, int, int] | None = None
        self.state: TargetState | None = None

    def ensure(self, depth_view: Any, width: int, height: int) -> None:
        """Targets, framebuffer and begin infos for a target of this size and depth (made again
        when either changes: the caller's frames in flight are waited for)."""
        key = (depth_view, width, height)
        if self._made_for == key:
            return
        vk = self.vk
        self.device.wait_idle()
        self._release_targets()
        color = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
        aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT
        for fmt in (ACCUMULATION_FORMAT, REVEALAGE_FORMAT):
            self.images.append(Image(self.device, width, height, getattr(vk, fmt), color, aspect))
        views = [image.view for image in self.images] + [depth_view]
        self.framebuffer = create_framebuffer(self.device, self.render_pass, views, width, height)
        read = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        for binding, image in enumerate(self.images):
            info = vk.VkDescriptorImageInfo(sampler=self.sampler, imageView=image.view, imageLayout=read)
            write_images(self.device, self.descriptor_set, binding, [info])
        state = TargetState.make(
            vk,
            (int(vk.ffi.cast("uintptr_t", self.framebuffer)), width, height),
            self.framebuffer,
            self.render_pass,
            self.secondaries.begin_info(self.render_pass, 0, self.framebuffer),
            (0.0, 0.0, 0.0),
        )
        # clear values in attachment order: accumulation 0, revealage 1 (depth is loaded)
        zero = vk.VkClearValue(color=vk.VkClearColorValue(float32=[0.0, 0.0, 0.0, 0.0]))
        one = vk.VkClearValue(color=vk.VkClearColorValue(float32=[1.0, 1.0, 1.0, 1.0]))
        clears = [zero, one, zero]
        begin = vk.VkRenderPassBeginInfo(
            renderPass=self.render_pass, framebuffer=self.framebuffer, renderArea=state.area, pClearValues=clears
        )
        state.keep += [clears, begin]
        state.pass_begin_ptr = vk.ffi.addressof(begin)
        self.state = state
        self._made_for = key

    def accumulate(self, cb: Any, secondary: Any) -> None:
        """The blended rows' secondary (recorded with `state.secondary_begin`) in the pass."""
        assert self.state is not None
        vk = self.vk
        vk.lib.vkCmdBeginRenderPass(cb, self.state.pass_begin_ptr, vk.VK_SUBPASS_CONTENTS_SECONDARY_COMMAND_BUFFERS)
        vk.lib.vkCmdExecuteCommands(cb, 1, vk.ffi.new("VkCommandBuffer[]", [secondary]))
        vk.lib.vkCmdEndRenderPass(cb)

    def record_composite(self, target_pass: Any, state: TargetState, slot: int) -> Any:
        """The composite's secondary in the target pass's first subpass (after the set-aside rows)."""
        if self.composite is None or self._composite_pass != target_pass:
            self._destroy_composite()
            spec = GraphicsPipelineSpec(
                "tonemap.vert",  # one triangle over the screen
                "oit_composite.frag",
                layout=self.layout,
                render_pass=target_pass,
                cull_back=False,
                depth_test=False,
                depth_write=False,
                blend="composite",
            )
            self.composite, self._composite_pass = graphics_pipeline(self.device, spec), target_pass
        return full_screen_secondary(self.secondaries, slot, state, self.composite, self.layout, self.set_array)

    def _destroy_composite(self) -> None:
        if self.composite is not None:
            self.vk.vkDestroyPipeline(self.device.handle, self.composite, None)
            self.composite = None

    def _release_targets(self) -> None:
        if self.framebuffer is not None:
            self.vk.vkDestroyFramebuffer(self.device.handle, self.framebuffer, None)
            self.framebuffer = None
        for image in self.images:
            image.destroy()
        self.images = []
        self._made_for, self.state = None, None

    def destroy(self) -> None:
        vk, handle = self.vk, self.device.handle
        self._release_targets()
        self._destroy_composite()
        vk.vkDestroyPipelineLayout(handle, self.layout, None)
        self.pool.destroy()
        self.set_layout.destroy()
        vk.vkDestroySampler(handle, self.sampler, None)
        vk.vkDestroyRenderPass(handle, self.render_pass, None)
