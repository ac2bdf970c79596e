"""Point and spot lights drawn as camera-facing billboards after the scene's meshes, in the same
rendering (into the HDR colour, multisampled like the scene, or the target), blended back to
front (light_rows.py sorts them far to near). A rendering whose draws come from secondaries takes
nothing else, so the billboards are a secondary of their own, recorded on the main thread. The
pipeline is made the first frame a scene has lights (a scene without lights never builds it),
once per set of attachment formats it is drawn into."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...gpu.device import Device
from ...gpu.pipeline import AttachmentFormats, GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ...gpu.secondary import SecondaryBuffers, end_command_buffer
from ..draw.path import TargetState
from ..layouts import BILLBOARD_PUSH


class LightPass:
    def __init__(self, device: Device, frame_set_layout: Any, secondaries: SecondaryBuffers, size: float = 0.08):
        vk = self.vk = device.vk
        self.device = device
        self.secondaries = secondaries
        self.size = size
        self.layout = pipeline_layout(
            device, [frame_set_layout], [(vk.VK_SHADER_STAGE_VERTEX_BIT, 0, BILLBOARD_PUSH.size)]
        )
        self.pipelines: dict[AttachmentFormats, Any] = {}
        self.pipeline: Any = None  # the last frame's (None until a scene has lights)
        self._push = np.zeros(1, dtype=BILLBOARD_PUSH.dtype)
        self._push_ptr = vk.ffi.from_buffer(self._push)

    def _pipeline(self, formats: AttachmentFormats) -> Any:
        pipeline = self.pipelines.get(formats)
        if pipeline is None:
            spec = GraphicsPipelineSpec(
                "light.vert",
                "light.frag",
                layout=self.layout,
                cull_back=False,
                depth_write=False,
                alpha_blend=True,
                **formats.spec_kwargs(),
            )
            pipeline = self.pipelines[formats] = graphics_pipeline(self.device, spec)
        return pipeline

    def record(
        self, slot: int, target: TargetState, formats: AttachmentFormats, set_array: Any, count: int
    ) -> tuple[Any, int]:
        """(the secondary drawing `count` billboards into attachments of `formats`, begun with
        the target's scene begin info, or None without any; the draws recorded). Raw calls,
        structs made once."""
        if count == 0:
            return None, 0
        vk = self.vk
        lib = vk.lib
        pipeline = self.pipeline = self._pipeline(formats)
        cb = self.secondaries.begin(slot, target.aside_begin)
        lib.vkCmdSetViewport(cb, 0, 1, target.viewport_ptr)
        lib.vkCmdSetScissor(cb, 0, 1, target.area_ptr)
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
        lib.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1, set_array, 0, vk.ffi.NULL
        )
        self._push["size"] = self.size
        lib.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_VERTEX_BIT, 0, BILLBOARD_PUSH.size, self._push_ptr)
        lib.vkCmdDraw(cb, 6, count, 0, 0)
        end_command_buffer(vk, cb)
        return cb, 1

    def forget_pipelines(self) -> None:
        """Made again from the shader files on next use (hot reload; the caller waited for the device)."""
        for pipeline in self.pipelines.values():
            self.vk.vkDestroyPipeline(self.device.handle, pipeline, None)
        self.pipelines, self.pipeline = {}, None

    def destroy(self) -> None:
        self.forget_pipelines()
        self.vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
