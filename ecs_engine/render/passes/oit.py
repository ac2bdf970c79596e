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
lighting dispatch, a pass of its own (the output graph's oit_accumulate) draws the blended
rows (mesh_*_oit.frag, the "weighted" blend, gpu/pipeline.py) into the two targets against the
G-buffer's depth (read-only, no writes); the composite (oit_composite.frag) is the last
secondary of the scene's rendering before the billboards, after the sky and the other set-aside
rows.

Known limit: blended surfaces are depth-tested against the G-buffer's opaque meshes only, not
against the rows drawn forward after the lighting (mirroring, wireframe and point materials),
which the composite then draws over where a transparent surface lies behind them.
"""

from __future__ import annotations

from typing import Any

from ...gpu.array_image import clamped_sampler
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_images
from ...gpu.device import Device
from ...gpu.pipeline import AttachmentFormats, GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ...gpu.scene_attachments import DEPTH_FORMAT_NAME
from ...gpu.secondary import SecondaryBuffers
from ..config import Transparency
from ..draw.path import TargetState
from .sky import full_screen_secondary

ACCUMULATION_FORMAT = "VK_FORMAT_R16G16B16A16_SFLOAT"
REVEALAGE_FORMAT = "VK_FORMAT_R16_SFLOAT"
TRANSPARENCY_MODES = Transparency.names()


class WeightedTransparency:
    """The pass, its targets (made for a target's size and depth), and the composite."""

    def __init__(self, device: Device, secondaries: SecondaryBuffers) -> None:
        self.device, self.vk, self.secondaries = device, device.vk, secondaries
        vk = self.vk
        # the accumulation pass's attachments: the two targets and depth (read-only), one sample
        colors = (getattr(vk, ACCUMULATION_FORMAT), getattr(vk, REVEALAGE_FORMAT))
        self.formats = AttachmentFormats(colors, getattr(vk, DEPTH_FORMAT_NAME), 1)
        self.sampler = clamped_sampler(device, max_lod=0.0)
        sampler = vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
        self.set_layout = DescriptorSetLayout(device, [(b, sampler, vk.VK_SHADER_STAGE_FRAGMENT_BIT) for b in (0, 1)])
        self.pool = DescriptorPool(device, 1, {sampler: 2})
        self.descriptor_set = self.pool.allocate(self.set_layout)
        self.set_array = vk.ffi.new("VkDescriptorSet[1]", [self.descriptor_set])
        self.layout = pipeline_layout(device, [self.set_layout.handle])
        self.composites: dict[AttachmentFormats, Any] = {}  # per formats of the scene it is drawn over
        self._named: tuple[Any, ...] | None = None  # the targets the composite's set names
        self._made_for: tuple[Any, int, int] | None = None
        self.state: TargetState | None = None

    def ensure(self, depth: Any, width: int, height: int) -> None:
        """The begin infos for a target of this size and depth (made again when either
        changes). `depth` is the target's depth Image (gpu/memory.py). The two targets are
        transients of the output graph (its oit_accumulate pass, render/passes/deferred_passes.py,
        creates and clears them; the graph places the barriers and may alias them with the
        G-buffer, dead by then)."""
        key = (depth.view, width, height)
        if self._made_for == key:
            return
        vk = self.vk
        self.state = TargetState.make(
            vk,
            (int(vk.ffi.cast("uintptr_t", depth.view)), width, height),
            None,  # dynamic rendering: no framebuffer or render pass (accumulate)
            self.secondaries.begin_info_rendering(self.formats),
            (0.0, 0.0, 0.0),
        )
        self._made_for = key

    def name_targets(self, targets: tuple[Any, ...]) -> None:
        """Point the composite's set at the two targets (the graph's GraphImages, kept: a new
        compile makes new ones, whose views may reuse destroyed ones' handle values), before
        the composite is recorded; the frames in flight are waited for when they change."""
        if self._named is not None and all(a is b for a, b in zip(self._named, targets, strict=True)):
            return
        if self._named is not None:
            self.device.wait_idle()  # frames in flight bind the set
        vk = self.vk
        read = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        for binding, image in enumerate(targets):
            info = vk.VkDescriptorImageInfo(sampler=self.sampler, imageView=image.view, imageLayout=read)
            write_images(self.device, self.descriptor_set, binding, [info])
        self._named = tuple(targets)

    def record_composite(self, formats: AttachmentFormats, state: TargetState, slot: int) -> Any:
        """The composite's secondary in the scene's rendering (attachments of `formats`), after the
        set-aside rows."""
        composite = self.composites.get(formats)
        if composite is None:
            spec = GraphicsPipelineSpec(
                "tonemap.vert",  # one triangle over the screen
                "oit_composite.frag",
                layout=self.layout,
                cull_back=False,
                depth_test=False,
                depth_write=False,
                blend="composite",
                **formats.spec_kwargs(),
            )
            composite = self.composites[formats] = graphics_pipeline(self.device, spec)
        return full_screen_secondary(self.secondaries, slot, state, composite, self.layout, self.set_array)

    def forget_composites(self) -> None:
        for composite in self.composites.values():
            self.vk.vkDestroyPipeline(self.device.handle, composite, None)
        self.composites = {}

    def _release_targets(self) -> None:
        self._made_for, self.state, self._named = None, None, None

    def destroy(self) -> None:
        vk, handle = self.vk, self.device.handle
        self._release_targets()
        self.forget_composites()
        vk.vkDestroyPipelineLayout(handle, self.layout, None)
        self.pool.destroy()
        self.set_layout.destroy()
        vk.vkDestroySampler(handle, self.sampler, None)
