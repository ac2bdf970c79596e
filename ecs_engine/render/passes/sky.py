"""The Environment's sky (components/environment.py) behind the scene: one full-screen triangle
at depth 0, the far plane of reverse-Z, whose depth test passes on equal, so it shades only
pixels no mesh covered. Recorded into a secondary of the scene's rendering after the chunks' and
before the set-aside rows' (blended ones must blend over it); in the deferred form, first in the
scene's rendering, over the lit G-buffer image. The pipeline is made the first frame a world has
a sky, once per set of attachment formats it is drawn into."""

from __future__ import annotations

from typing import Any

from ...gpu.device import Device
from ...gpu.pipeline import AttachmentFormats, GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ...gpu.secondary import SecondaryBuffers, end_command_buffer
from ..draw.path import TargetState


def full_screen_secondary(
    secondaries: SecondaryBuffers, slot: int, state: TargetState, pipeline: Any, layout: Any, set_array: Any
) -> Any:
    """A secondary of the scene's rendering (its set-aside begin info) drawing one
    triangle over the screen with `pipeline` and set 0 `set_array`: the sky, and weighted
    transparency's composite (oit_pass.py). Raw calls, structs made once."""
    vk = secondaries.device.vk
    lib = vk.lib
    cb = secondaries.begin(slot, state.aside_begin)
    lib.vkCmdSetViewport(cb, 0, 1, state.viewport_ptr)
    lib.vkCmdSetScissor(cb, 0, 1, state.area_ptr)
    lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
    lib.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0, 1, set_array, 0, vk.ffi.NULL)
    lib.vkCmdDraw(cb, 3, 1, 0, 0)
    end_command_buffer(vk, cb)
    return cb


class SkyPass:
    def __init__(self, device: Device, frame_set_layout: Any, secondaries: SecondaryBuffers) -> None:
        self.device, self.vk, self.secondaries = device, device.vk, secondaries
        self.layout = pipeline_layout(device, [frame_set_layout])
        self.pipelines: dict[AttachmentFormats, Any] = {}  # per formats drawn into

    def record(self, state: TargetState, set_array: Any, slot: int, formats: AttachmentFormats) -> Any:
        """The sky's secondary for this frame, drawn into attachments of `formats`."""
        pipeline = self.pipelines.get(formats)
        if pipeline is None:
            spec = GraphicsPipelineSpec(
                "sky.vert",
                "sky.frag",
                layout=self.layout,
                cull_back=False,
                depth_write=False,
                depth_or_equal=True,
                **formats.spec_kwargs(),
            )
            pipeline = self.pipelines[formats] = graphics_pipeline(self.device, spec)
        return full_screen_secondary(self.secondaries, slot, state, pipeline, self.layout, set_array)

    def forget_pipelines(self) -> None:
        """Made again from the shader files on next use (hot reload; the caller waited for the device)."""
        for pipeline in self.pipelines.values():
            self.vk.vkDestroyPipeline(self.device.handle, pipeline, None)
        self.pipelines = {}

    def destroy(self) -> None:
        self.forget_pipelines()
        self.vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
