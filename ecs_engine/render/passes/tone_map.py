"""The tone map: the scene is lit in 16-bit float colour (gpu/scene_attachments.py); this pass scales
it by the exposure and maps it into what the display shows, drawn with dynamic rendering into the
target after the scene's rendering and the post effects (render/frame/output_passes.py), reading the
HDR colour as a sampled image with texelFetch (the same pixel, unfiltered).

Operators (TONE_MAPS, picked by name; the shader reads the number):

- `clamp`: min(c, 1), what the engine drew before HDR (the default: the seed scenes keep their
  look and golden images);
- `aces`: Narkowicz's fit of the ACES filmic curve, a toe and a soft shoulder, so highlights
  keep their shape instead of burning out;
- `reinhard`: c / (1 + c).

`exposure` is in stops (EV): the colour is multiplied by 2^EV before the curve.
"""

from __future__ import annotations

from typing import Any, Final

import numpy as np

from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout
from ...gpu.device import Device
from ...gpu.pipeline import GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ..config import ToneMap
from ..layouts import TONE_MAP_ACES, TONE_MAP_CLAMP, TONE_MAP_PUSH, TONE_MAP_REINHARD

# the operators by config.ToneMap name (a member is its name: TONE_MAPS["aces"])
TONE_MAPS: Final[dict[str, int]] = {
    ToneMap.CLAMP: TONE_MAP_CLAMP,
    ToneMap.ACES: TONE_MAP_ACES,
    ToneMap.REINHARD: TONE_MAP_REINHARD,
}
_SETS = 8  # descriptor sets kept, one per HDR view seen (swapchains come and go)
# the push constants: ToneMapPush, then the view's offset in the target (tonemap.frag's `offset`)
_PUSH = np.dtype([("push", TONE_MAP_PUSH.dtype), ("offset", "<i4", (2,))])


def wants_hdr(name: str, exposure: float, samples: int, blends: bool = False, post: bool = False) -> bool:
    """Whether the scene must be lit in HDR colour and tone mapped: not for the clamp operator at
    exposure 0 without MSAA, which the target's own sRGB encoding does as well (gpu/scene_attachments.py),
    unless some material blends: an 8-bit target clamps a blended colour before blending (glass lit
    to 3.0 at alpha 0.5 over black: 0.5), the HDR colour after (1.0); or post effects are on (they
    run on the HDR colour, or between the tone map and the target: output_passes.py)."""
    return name != ToneMap.CLAMP or exposure != 0.0 or samples > 1 or blends or post


class ToneMapPass:
    """The full-screen triangle into a target of `color_format` (pipeline made at first use)."""

    def __init__(self, device: Device, color_format: int) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.color_format = color_format
        stage = vk.VK_SHADER_STAGE_FRAGMENT_BIT
        self.set_layout = DescriptorSetLayout(device, [(0, vk.VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE, stage)])
        self.pool: DescriptorPool | None = None
        self._sets: dict[int, Any] = {}  # HDR view address -> VkDescriptorSet[1]
        self._views = 0  # the target's attachment remakes the sets were made for
        self.layout = pipeline_layout(device, [self.set_layout.handle], [(stage, 0, _PUSH.itemsize)])
        self.pipeline: Any = None
        self._all = np.zeros(1, dtype=_PUSH)
        self._push = self._all["push"]
        self._offset = self._all["offset"][0]
        self._at: tuple[int, int] | None = None  # the offset pushed (None: none, zeros)
        self._push_ptr = vk.ffi.from_buffer(self._all)

    def _set_for(self, view: Any) -> Any:
        vk = self.vk
        key = int(vk.ffi.cast("uintptr_t", view))
        found = self._sets.get(key)
        if found is not None:
            return found
        if self.pool is None or len(self._sets) >= _SETS:
            if self.pool is not None:
                self.device.wait_idle()  # the old sets may be bound by frames in flight
                self.pool.destroy()
            self.pool = DescriptorPool(self.device, _SETS, {vk.VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE: _SETS})
            self._sets.clear()
        descriptor_set = self.pool.allocate(self.set_layout)
        info = vk.VkDescriptorImageInfo(imageView=view, imageLayout=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL)
        write = vk.VkWriteDescriptorSet(
            dstSet=descriptor_set,
            dstBinding=0,
            dstArrayElement=0,
            descriptorCount=1,
            descriptorType=vk.VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE,
            pImageInfo=[info],
        )
        self.device.objects_version += 1
        vk.vkUpdateDescriptorSets(self.device.handle, 1, [write], 0, None)
        found = self._sets[key] = vk.ffi.new("VkDescriptorSet[1]", [descriptor_set])
        return found

    def record(
        self,
        cb: Any,
        state: Any,
        target: Any,
        name: str,
        exposure: float,
        offset: tuple[int, int] | None = None,
    ) -> None:
        """The full-screen triangle over `state`'s area (raw calls, inside the output's
        vkCmdBeginRendering), reading `target`'s HDR view; with `offset` (a view's rectangle
        of the target: render/frame/view_graph.py) over the rendering's area instead, whose
        viewport begin_rendering set, the HDR colour read from its corner;
        the set per view made once. A swapchain counts its remakes (`recreations`): a new view may
        reuse an old one's handle value, so the sets made for the old views go then."""
        vk = self.vk
        lib = vk.lib
        viewport_ptr, area_ptr, hdr_view = state.viewport_ptr, state.area_ptr, target.hdr_view
        views = getattr(target, "recreations", 0)
        if views != self._views:
            self.device.wait_idle()  # (the remake waited already; frames in flight may bind the sets)
            if self.pool is not None:
                self.pool.destroy()
                self.pool = None
            self._sets.clear()
            self._views = views
        if self.pipeline is None:
            self.pipeline = graphics_pipeline(
                self.device,
                GraphicsPipelineSpec(
                    "tonemap.vert",
                    "tonemap.frag",
                    layout=self.layout,
                    render_pass=None,
                    color_formats=(self.color_format,),
                    cull_back=False,
                    depth_test=False,
                    depth_write=False,
                ),
            )
        descriptor_set = self._set_for(hdr_view)
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.pipeline)
        if offset is None:
            lib.vkCmdSetViewport(cb, 0, 1, viewport_ptr)
            lib.vkCmdSetScissor(cb, 0, 1, area_ptr)
        if offset != self._at:  # (the window's one view: never)
            self._offset[:] = offset or (0, 0)
            self._at = offset
        lib.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1, descriptor_set, 0, vk.ffi.NULL
        )
        self._push["exposure"] = 2.0**exposure
        self._push["operator"] = TONE_MAPS[name]
        lib.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_FRAGMENT_BIT, 0, _PUSH.itemsize, self._push_ptr)
        lib.vkCmdDraw(cb, 3, 1, 0, 0)

    def destroy(self) -> None:
        vk = self.vk
        if self.pipeline is not None:
            vk.vkDestroyPipeline(self.device.handle, self.pipeline, None)
        vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
        if self.pool is not None:
            self.pool.destroy()
        self.set_layout.destroy()
