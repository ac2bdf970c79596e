"""Point and spot lights drawn as camera-facing billboards in the billboard subpass (into the HDR
colour, multisampled like the scene), blended back to front
(light_rows.py sorts them far to near). The pipeline is made the first frame a scene has
lights: a scene without lights never builds it."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..gpu.device import Device
from ..gpu.pipeline import GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from .layouts import BILLBOARD_PUSH
from .path import TargetState


class LightPass:
    def __init__(
        self,
        device: Device,
        frame_set_layout: Any,
        render_pass: Any,
        subpass: int,
        size: float = 0.08,
        samples: int = 1,
    ) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.render_pass = render_pass
        self.subpass = subpass
        self.samples = samples
        self.size = size
        self.layout = pipeline_layout(
            device, [frame_set_layout], [(vk.VK_SHADER_STAGE_VERTEX_BIT, 0, BILLBOARD_PUSH.size)]
        )
        self.pipeline: Any = None
        self._push = np.zeros(1, dtype=BILLBOARD_PUSH.dtype)
        self._push_ptr = vk.ffi.from_buffer(self._push)

    def record(self, cb: Any, target: TargetState, set_array: Any, count: int) -> int:
        """Draw `count` billboards (raw calls, structs made once); returns the draws recorded."""
        if count == 0:
            return 0
        vk = self.vk
        lib = vk.lib
        if self.pipeline is None:
            self.pipeline = graphics_pipeline(
                self.device,
                GraphicsPipelineSpec(
                    "light.vert",
                    "light.frag",
                    layout=self.layout,
                    render_pass=self.render_pass,
                    subpass=self.subpass,
                    cull_back=False,
                    depth_write=False,
                    alpha_blend=True,
                    samples=self.samples,
                ),
            )
        lib.vkCmdSetViewport(cb, 0, 1, target.viewport_ptr)
        lib.vkCmdSetScissor(cb, 0, 1, target.area_ptr)
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.pipeline)
        lib.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1, set_array, 0, vk.ffi.NULL
        )
        self._push["size"] = self.size
        lib.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_VERTEX_BIT, 0, BILLBOARD_PUSH.size, self._push_ptr)
        lib.vkCmdDraw(cb, 6, count, 0, 0)
        return 1

    def retarget(self, render_pass: Any) -> None:
        """Draw into another render pass (the pipeline is made again on first use)."""
        if self.pipeline is not None:
            self.vk.vkDestroyPipeline(self.device.handle, self.pipeline, None)
            self.pipeline = None
        self.render_pass = render_pass

    def destroy(self) -> None:
        if self.pipeline is not None:
            self.vk.vkDestroyPipeline(self.device.handle, self.pipeline, None)
        self.vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
