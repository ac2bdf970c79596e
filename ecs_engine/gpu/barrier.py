"""A global memory barrier made once and recorded with a raw call (the per-frame passes record
several a frame; the binding's wrapper costs microseconds each)."""

from __future__ import annotations

from typing import Any


class Barrier:
    """A global memory barrier, made once and recorded with a raw call."""

    def __init__(self, vk: Any, src_stage: int, dst_stage: int, src_access: int, dst_access: int) -> None:
        self.stages = (src_stage, dst_stage)
        self.barrier = vk.ffi.new(
            "VkMemoryBarrier*",
            {"sType": vk.VK_STRUCTURE_TYPE_MEMORY_BARRIER, "srcAccessMask": src_access, "dstAccessMask": dst_access},
        )
        self.null = vk.ffi.NULL

    def record(self, lib: Any, cb: Any) -> None:
        lib.vkCmdPipelineBarrier(cb, self.stages[0], self.stages[1], 0, 1, self.barrier, 0, self.null, 0, self.null)
