"""What the GPU tests of frame-graph passes share to read an image back: a copy's writes made
visible to the host before the test maps the buffer (the graph has no host access of its own)."""

from __future__ import annotations

from typing import Any


def host_barrier(vk: Any, cb: Any) -> None:
    """The transfer writes recorded so far, visible to the host once the submission is waited for."""
    to_host = vk.VkMemoryBarrier2(
        srcStageMask=vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT,
        srcAccessMask=vk.VK_ACCESS_2_TRANSFER_WRITE_BIT,
        dstStageMask=vk.VK_PIPELINE_STAGE_2_HOST_BIT,
        dstAccessMask=vk.VK_ACCESS_2_HOST_READ_BIT,
    )
    vk.vkCmdPipelineBarrier2(cb, vk.VkDependencyInfo(pMemoryBarriers=[to_host]))
