"""The ray-traced shadows' small denoise (shaders/shadow_denoise.comp), an option of
render/raytracing/shadows.py (on by default): the mask of an area light, traced with a few rays a pixel,
averaged over 5 x 5 pixels of alike surfaces into the mask the deferred lighting reads; a hard
shadow's mask copied as it is."""

from __future__ import annotations

from typing import Any

from ...gpu.array_image import nearest_sampler
from ...gpu.barrier import Barrier
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_set
from ...gpu.owned import Owned
from ...gpu.pipeline import compute_pipeline, pipeline_layout
from ..layouts import BINDING_RAY_DENOISED, BINDING_RAY_DEPTH, BINDING_RAY_FRAME, BINDING_RAY_MASK, BINDING_RAY_NORMAL

GROUP = 8  # shadow_denoise.comp's local size, each way


class ShadowDenoise:
    def __init__(self, device: Any, frames: int) -> None:
        vk = device.vk
        self.device = device
        stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
        image = vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE
        self.owned = owned = Owned(device)
        try:
            self.set_layout = owned.add(
                DescriptorSetLayout(
                    device,
                    [
                        (BINDING_RAY_FRAME, vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, stage),
                        (BINDING_RAY_DEPTH, vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, stage),
                        (BINDING_RAY_NORMAL, image, stage),
                        (BINDING_RAY_MASK, image, stage),
                        (BINDING_RAY_DENOISED, image, stage),
                    ],
                )
            )
            sizes = {
                vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER: frames,
                vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: frames,
                image: 3 * frames,
            }
            self.pool = owned.add(DescriptorPool(device, frames, sizes))
            handle = device.handle
            layout = self.layout = pipeline_layout(device, [self.set_layout.handle])
            owned.add(layout, lambda: vk.vkDestroyPipelineLayout(handle, layout, None))
            pipeline = self.pipeline = compute_pipeline(device, "shadow_denoise.comp", layout)
            owned.add(pipeline, lambda: vk.vkDestroyPipeline(handle, pipeline, None))
            sampler = self.sampler = nearest_sampler(device)
            owned.add(sampler, lambda: vk.vkDestroySampler(handle, sampler, None))
            self.sets = [self.pool.allocate(self.set_layout) for _ in range(frames)]
        except BaseException:
            owned.destroy()
            raise
        self.named: list[tuple[Any, ...]] = [() for _ in range(frames)]
        compute = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
        self._after = Barrier(vk, compute, compute, vk.VK_ACCESS_SHADER_WRITE_BIT, vk.VK_ACCESS_SHADER_READ_BIT)

    def record(
        self, cb: Any, slot: int, frame: Any, attachments: Any, traced: Any, out: Any, width: int, height: int
    ) -> None:
        """Filter `traced` (ShadowMask) into `out` for the lighting after it (a barrier ends it)."""
        vk = self.device.vk
        named = (frame, attachments, traced, out)
        if self.named[slot] != named:
            self._name(self.sets[slot], frame, attachments, traced, out)
            self.named[slot] = named
        point = vk.VK_PIPELINE_BIND_POINT_COMPUTE
        vk.lib.vkCmdBindPipeline(cb, point, self.pipeline)
        sets = vk.ffi.new("VkDescriptorSet[1]", [self.sets[slot]])
        vk.lib.vkCmdBindDescriptorSets(cb, point, self.layout, 0, 1, sets, 0, vk.ffi.NULL)
        vk.lib.vkCmdDispatch(cb, -(-width // GROUP), -(-height // GROUP), 1)
        self._after.record(vk.lib, cb)

    def _name(self, descriptor_set: Any, frame: Any, attachments: Any, traced: Any, out: Any) -> None:
        depth_layout = self.device.vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL
        write_set(
            self.device,
            descriptor_set,
            storage_buffers=[(BINDING_RAY_FRAME, frame)],
            samplers=[(BINDING_RAY_DEPTH, self.sampler, attachments.depth_view, depth_layout)],
            storage_images=[
                (BINDING_RAY_NORMAL, attachments.gbuffer.views[0]),
                (BINDING_RAY_MASK, traced.view),
                (BINDING_RAY_DENOISED, out.view),
            ],
        )

    def destroy(self) -> None:
        self.owned.destroy()  # the sampler, pipeline, pipeline layout, pool (its sets), set layout
