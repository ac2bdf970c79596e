"""Deferred lighting of the opaque meshes, in compute, between the G-buffer's rendering and the
scene's (the deferred form, gpu/scene_attachments.py): the G-buffer (gpu/gbuffer.py) leaves depth, the HDR
colour with ambient and emissive, and per pixel normal, roughness, base colour, metallic and the
material index; deferred_light.comp adds every light's term, the same light_term the forward
fragment shader uses, walking the light grid of render/lighting/clusters.py per 16 x 16-pixel
workgroup when there is one. Blended materials and materials with a fill of their own stay
forward (set_aside_pass.py), drawn in the scene's rendering over the lit scene.

Why it exists: on the H100, fragment shaders run on the few graphics-capable units of the chip and
compute shaders on all of it; the forward frame with 4,096 clustered lights took 3.97x the 6-light
one (docs/performance.md has the figures before and after).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...gpu.array_image import nearest_sampler
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_set
from ...gpu.device import Device
from ...gpu.pipeline import compute_pipeline, pipeline_layout
from ..layouts import (
    BINDING_BASE_METALLIC,
    BINDING_DEPTH,
    BINDING_HDR,
    BINDING_MATERIAL_IDS,
    BINDING_NORMAL_ROUGHNESS,
    BINDING_SHADOW_MASK,
    DEFERRED_PUSH,
    DEFERRED_TILE,
)
from ..raytracing.mask import ShadowMask


class DeferredPass:
    def __init__(self, device: Device, frame_set_layout: Any) -> None:
        vk = self.vk = device.vk
        self.device = device
        stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
        storage = vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE
        sampled = vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
        self.set_layout = DescriptorSetLayout(
            device,
            [(BINDING_DEPTH, sampled, stage)]
            + [(b, storage, stage) for b in (BINDING_HDR, BINDING_NORMAL_ROUGHNESS, BINDING_BASE_METALLIC)]
            + [(BINDING_MATERIAL_IDS, storage, stage), (BINDING_SHADOW_MASK, storage, stage)],
        )
        self.pool: DescriptorPool | None = None
        self.layout = None
        self.sampler = None
        try:
            self.pool = DescriptorPool(device, 1, {sampled: 1, storage: 5})
            self.layout = pipeline_layout(
                device, [frame_set_layout, self.set_layout.handle], [(stage, 0, DEFERRED_PUSH.size)]
            )
            self.sampler = nearest_sampler(device)
            self.image_set = self.pool.allocate(self.set_layout)
        except BaseException:
            self.destroy()
            raise
        self.pipelines: dict[int, Any] = {}  # MATERIAL_FEATURES -> pipeline
        self._named: Any = None  # the target's SceneAttachments the set names
        self.mask: ShadowMask | None = None  # ray-traced shadows' mask, made with the attachments named
        # whether the mask is traced into (the renderer traces shadows): else it is never read
        # (deferred_light.comp reads it under FEATURE_RAY_SHADOWS alone) and one pixel is enough
        self.traced = True
        self._push = np.zeros(1, DEFERRED_PUSH.dtype)
        self._push_ptr = vk.ffi.from_buffer(self._push)

    def _name(self, attachments: Any) -> None:
        """Point set 1 at a target's depth, HDR colour and G-buffer (once per attachments: a
        swapchain remakes them on resize, and frames in flight must be done with the old ones)."""
        self.device.wait_idle()
        gbuffer = attachments.gbuffer
        hdr = attachments.images[1]
        if self.mask is not None:
            self.mask.destroy()
            self.mask = None
        self.mask = ShadowMask(self.device, *((hdr.width, hdr.height) if self.traced else (1, 1)))
        views = [(BINDING_HDR, hdr.view)] + list(
            zip((BINDING_NORMAL_ROUGHNESS, BINDING_BASE_METALLIC, BINDING_MATERIAL_IDS), gbuffer.views, strict=True)
        )
        views.append((BINDING_SHADOW_MASK, self.mask.view))
        depth_layout = self.vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL
        samplers = [(BINDING_DEPTH, self.sampler, attachments.depth_view, depth_layout)]
        write_set(self.device, self.image_set, samplers=samplers, storage_images=views)
        self._named = attachments

    def named(self, attachments: Any) -> ShadowMask:
        """The shadow mask of the set, once the set names `attachments`."""
        if attachments is not self._named:
            self._name(attachments)
        assert self.mask is not None
        return self.mask

    def record(self, cb: Any, frame_set: Any, attachments: Any, features: int, width: int, height: int) -> None:
        """Light the G-buffer of `attachments` (between the G-buffer pass and the target's pass,
        whose dependencies order the images); `features`: the mesh pipelines' MATERIAL_FEATURES."""
        vk = self.vk
        if attachments is not self._named:
            self._name(attachments)
        pipeline = self.pipelines.get(features)
        if pipeline is None:
            pipeline = self.pipelines[features] = compute_pipeline(
                self.device, "deferred_light.comp", self.layout, (features,)
            )
        point = vk.VK_PIPELINE_BIND_POINT_COMPUTE
        vk.vkCmdBindPipeline(cb, point, pipeline)
        vk.vkCmdBindDescriptorSets(cb, point, self.layout, 0, 2, [frame_set, self.image_set], 0, None)
        self._push["viewport"] = (width, height)
        stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
        vk.lib.vkCmdPushConstants(cb, self.layout, stage, 0, DEFERRED_PUSH.size, self._push_ptr)
        vk.vkCmdDispatch(cb, -(-width // DEFERRED_TILE), -(-height // DEFERRED_TILE), 1)

    def destroy(self) -> None:
        vk, handle = self.vk, self.device.handle
        mask = getattr(self, "mask", None)
        if mask is not None:
            mask.destroy()
            self.mask = None
        for pipeline in getattr(self, "pipelines", {}).values():
            vk.vkDestroyPipeline(handle, pipeline, None)
        self.pipelines = {}
        if self.sampler is not None:
            vk.vkDestroySampler(handle, self.sampler, None)
            self.sampler = None
        if self.layout is not None:
            vk.vkDestroyPipelineLayout(handle, self.layout, None)
            self.layout = None
        if self.pool is not None:
            self.pool.destroy()
            self.pool = None
        self.set_layout.destroy()
