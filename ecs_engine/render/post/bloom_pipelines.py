"""The bloom's GPU objects, shared by all its passes (render/post/bloom.py): the two compute
pipelines (the first downsample is a specialisation of the downsample shader), the linear
clamp-to-edge sampler every step reads through, and the descriptor sets, one per pair of views
(the level read, the level written) seen."""

from __future__ import annotations

import struct
from typing import Any

from ...gpu.array_image import clamped_sampler
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_set
from ...gpu.owned import Owned
from ...gpu.pipeline import compute_pipeline, pipeline_layout

GROUP = 8  # the shaders' local size, each way
_SETS = 64  # descriptor sets kept: one per (read view, written view) pair; N + N passes a chain
# vec4 threshold (downsample) or float src, dst (upsample); then vec2 source_size, target_size
_PUSH_BYTES = 32


class BloomPipelines:
    """Made once per device and shared by a chain's passes; each pass `acquire`s it and
    `release`s it on destroy, the last release destroys it."""

    def __init__(self, device: Any) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.users = 0
        stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
        self.pool: DescriptorPool | None = None
        self.pipelines: dict[str, Any] = {}
        self._sets: dict[tuple[int, int], Any] = {}
        self._chain: object = None  # the chain image the sets were made for (held: its id stays unique)
        # the set layout, pipeline layout, pipelines and sampler; the pool, made again when its
        # sets run out or name stale views, released from it and added anew
        self.owned = owned = Owned(device)
        handle = device.handle
        try:
            self.set_layout = owned.add(
                DescriptorSetLayout(
                    device,
                    [
                        (0, vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, stage),
                        (1, vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, stage),
                    ],
                )
            )
            layout = self.layout = pipeline_layout(device, [self.set_layout.handle], [(stage, 0, _PUSH_BYTES)])
            owned.add(layout, lambda: vk.vkDestroyPipelineLayout(handle, layout, None))
            for kind, shader, constants in (
                ("first", "bloom_downsample.comp", (1,)),
                ("down", "bloom_downsample.comp", (0,)),
                ("up", "bloom_upsample.comp", ()),
            ):
                self.pipelines[kind] = self._own_pipeline(compute_pipeline(device, shader, layout, constants))
            # bilinear, clamped, LOD 0: each step reads one mip through its own view, and the
            # taps between texels are what makes 13 fetches cover 36 texels
            sampler = self.sampler = clamped_sampler(device, max_lod=0.0)
            owned.add(sampler, lambda: vk.vkDestroySampler(handle, sampler, None))
        except BaseException:
            self.destroy()
            raise
        self._push = vk.ffi.new("char[]", _PUSH_BYTES)

    def _own_pipeline(self, pipeline: Any) -> Any:
        vk, handle = self.vk, self.device.handle
        return self.owned.add(pipeline, lambda: vk.vkDestroyPipeline(handle, pipeline, None))

    def acquire(self) -> BloomPipelines:
        self.users += 1
        return self

    def release(self) -> None:
        self.users -= 1
        if self.users <= 0:
            self.destroy()

    def dispatch(
        self,
        cb: Any,
        kind: str,
        read_view: Any,
        write_view: Any,
        size: tuple[int, int],
        push: tuple[float, ...],
        source_size: tuple[int, int],
    ) -> None:
        """Record one step: pipeline `kind` ("first", "down", "up") reading the `source_size`
        rectangle at the corner of `read_view` (sampled, SHADER_READ_ONLY_OPTIMAL) and writing the
        `size` one of `write_view` (storage, GENERAL), with up to four floats of parameters. The
        rectangles are the graph's extents, not the images': a split-screen view imports a corner
        of the window's HDR image. Barriers are the frame graph's."""
        vk = self.vk
        lib = vk.lib
        point = vk.VK_PIPELINE_BIND_POINT_COMPUTE
        lib.vkCmdBindPipeline(cb, point, self.pipelines[kind])
        lib.vkCmdBindDescriptorSets(cb, point, self.layout, 0, 1, self._set_for(read_view, write_view), 0, vk.ffi.NULL)
        data = struct.pack(f"<{len(push)}f", *push).ljust(16, b"\0") + struct.pack("<4f", *source_size, *size)
        vk.ffi.memmove(self._push, data, _PUSH_BYTES)
        lib.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_COMPUTE_BIT, 0, _PUSH_BYTES, self._push)
        lib.vkCmdDispatch(cb, -(-size[0] // GROUP), -(-size[1] // GROUP), 1)

    def track(self, chain: object) -> None:
        """Called with the chain image (the graph's GraphImage) before each step: a different
        object means the graph was compiled again and made new transients, whose views may
        reuse the handle values of destroyed ones, so the sets made so far go."""
        if chain is not self._chain:
            if self._sets:
                self.device.wait_idle()
            self.forget_views()
            self._chain = chain

    def forget_views(self) -> None:
        """Drop every set (after the GPU is idle): call it when the views they name are
        destroyed, since a new view may come back with an old one's handle value."""
        if self.pool is not None:
            self.owned.release(self.pool)
            self.pool = None
        self._sets.clear()

    def _set_for(self, read_view: Any, write_view: Any) -> Any:
        """The set naming the two views, written once: a set is never rewritten, so a command
        buffer recorded with it (a replayed frame, a frame in flight) stays valid."""
        vk = self.vk
        key = (int(vk.ffi.cast("uintptr_t", read_view)), int(vk.ffi.cast("uintptr_t", write_view)))
        found = self._sets.get(key)
        if found is not None:
            return found
        if self.pool is None or len(self._sets) >= _SETS:
            self.device.wait_idle()  # the old sets may be bound by frames in flight
            self.forget_views()
            sizes = {vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: _SETS, vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE: _SETS}
            self.pool = self.owned.add(DescriptorPool(self.device, _SETS, sizes))
        descriptor_set = self.pool.allocate(self.set_layout)
        read_layout = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        write_set(
            self.device,
            descriptor_set,
            samplers=[(0, self.sampler, read_view, read_layout)],
            storage_images=[(1, write_view)],
        )
        found = self._sets[key] = vk.ffi.new("VkDescriptorSet[1]", [descriptor_set])
        return found

    def destroy(self) -> None:
        self.owned.destroy()  # the pool, sampler, pipelines, pipeline layout, set layout
        self.pool = None
        self._sets.clear()
        self.pipelines.clear()
