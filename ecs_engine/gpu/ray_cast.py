"""Cast a batch of rays into a top-level acceleration structure on the GPU and read the closest
hits back (shaders/ray_cast.*): what the ray-traced paths are checked with, and a way to pick or
probe the scene from the CPU where the device traces rays."""

from __future__ import annotations

from typing import Any

import numpy as np

from .acceleration import TopLevel
from .barrier import Barrier
from .descriptors import DescriptorPool, DescriptorSetLayout, write_acceleration_structure, write_buffers
from .memory import HOST, Buffer
from .owned import Owned
from .pipeline import pipeline_layout
from .ray_pipeline import RayPipeline

HIT_DTYPE = np.dtype([("t", "<f4"), ("custom_index", "<f4"), ("primitive", "<f4"), ("instance", "<f4")])


class RayCaster:
    """`cast(top, origins, directions)`: per ray, t of the closest hit (-1: none), the instance's
    custom index, the triangle and the instance, as HIT_DTYPE rows."""

    def __init__(self, device: Any) -> None:
        vk, lib = device.vk, device.vk.lib
        self.device = device
        stages = lib.VK_SHADER_STAGE_RAYGEN_BIT_KHR
        storage = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        # the set layout, pool, pipeline layout and pipeline; a failure half-way leaves nothing
        self.owned = owned = Owned(device)
        try:
            self.set_layout = owned.add(
                DescriptorSetLayout(
                    device,
                    [
                        (0, lib.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, stages),
                        (1, storage, stages),
                        (2, storage, stages),
                    ],
                )
            )
            sizes = {lib.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR: 1, storage: 2}
            self.pool = owned.add(DescriptorPool(device, 1, sizes))
            layout = self.layout = pipeline_layout(device, [self.set_layout.handle], [(stages, 0, 8)])
            owned.add(layout, lambda: vk.vkDestroyPipelineLayout(device.handle, layout, None))
            self.pipeline = owned.add(
                RayPipeline(device, self.layout, "ray_cast.rgen", ["ray_cast.rmiss"], ["ray_cast.rchit"])
            )
        except BaseException:
            owned.destroy()
            raise
        self.set = self.pool.allocate(self.set_layout)
        self.push = vk.ffi.new("uint32_t[2]")
        self._to_host = Barrier(
            vk,
            lib.VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
            vk.VK_PIPELINE_STAGE_HOST_BIT,
            vk.VK_ACCESS_SHADER_WRITE_BIT,
            vk.VK_ACCESS_HOST_READ_BIT,
        )

    def cast(
        self,
        top: TopLevel,
        origins: np.ndarray,
        directions: np.ndarray,
        t_min: float = 0.0,
        t_max: float = 1e30,
        mask: int = 0xFF,
    ) -> np.ndarray:
        """Rays from `origins` along `directions` (n, 3 each; not normalised: t is in their
        units); the top level must be built (its build recorded and submitted before)."""
        vk, lib = self.device.vk, self.device.vk.lib
        n = len(origins)
        rays = np.zeros((n, 2, 4), dtype=np.float32)
        rays[:, 0, :3], rays[:, 0, 3] = origins, t_min
        rays[:, 1, :3], rays[:, 1, 3] = directions, t_max
        usage, storage = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        ray_buffer = Buffer(self.device, max(rays.nbytes, 32), usage, HOST)
        hit_buffer = Buffer(self.device, max(n * HIT_DTYPE.itemsize, 16), usage, HOST)
        try:
            ray_buffer.bytes()[: rays.nbytes] = rays.view(np.uint8).reshape(-1)
            write_acceleration_structure(self.device, self.set, 0, top.handle)
            write_buffers(self.device, self.set, [(1, storage, ray_buffer), (2, storage, hit_buffer)])
            self.push[0], self.push[1] = n, mask

            def record(cb: Any) -> None:
                self.pipeline.bind(cb, [self.set])
                lib.vkCmdPushConstants(cb, self.layout, lib.VK_SHADER_STAGE_RAYGEN_BIT_KHR, 0, 8, self.push)
                self.pipeline.trace(cb, max(n, 1), 1)
                self._to_host.record(lib, cb)  # the hits, for the host to read

            self.device.submit_once(record)
            return hit_buffer.array(HIT_DTYPE, n).copy()
        finally:
            ray_buffer.destroy()
            hit_buffer.destroy()

    def destroy(self) -> None:
        self.owned.destroy()
