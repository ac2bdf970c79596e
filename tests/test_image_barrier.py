"""gpu/image_barrier.py, the one constructor of image barriers, without a device: every field
where it was asked for, and the frame graph's plan recorded through it."""

from __future__ import annotations

from test_frame_graph import make

from ecs_engine.gpu.image_barrier import dependency, image_barrier
from ecs_engine.gpu.loader import load_vulkan
from ecs_engine.render.graph import Access, ImageDesc, Load
from ecs_engine.render.graph.barriers import dependency_info

vk = load_vulkan()


def test_a_barrier_has_the_range_layouts_stages_and_accesses_asked_for():
    b = image_barrier(
        vk,
        vk.ffi.cast("VkImage", 0x1234),
        aspect=vk.VK_IMAGE_ASPECT_DEPTH_BIT,
        base_mip=2,
        mips=3,
        base_layer=4,
        layers=5,
        old=vk.VK_IMAGE_LAYOUT_UNDEFINED,
        new=vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        src_stage=vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
        src_access=vk.VK_ACCESS_2_NONE,
        dst_stage=vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
        dst_access=vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
    )
    assert b.sType == vk.VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2
    assert int(vk.ffi.cast("uintptr_t", b.image)) == 0x1234
    r = b.subresourceRange
    assert (r.aspectMask, r.baseMipLevel, r.levelCount, r.baseArrayLayer, r.layerCount) == (
        vk.VK_IMAGE_ASPECT_DEPTH_BIT, 2, 3, 4, 5,
    )  # fmt: skip
    assert (b.oldLayout, b.newLayout) == (
        vk.VK_IMAGE_LAYOUT_UNDEFINED,
        vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    )
    assert (b.srcStageMask, b.srcAccessMask) == (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0)
    assert b.dstStageMask == vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT
    assert b.dstAccessMask == vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
    assert b.srcQueueFamilyIndex == b.dstQueueFamilyIndex == vk.VK_QUEUE_FAMILY_IGNORED
    info = dependency(vk, [b, b])
    assert (info.imageMemoryBarrierCount, info.bufferMemoryBarrierCount, info.memoryBarrierCount) == (2, 0, 0)
    assert info.pImageMemoryBarriers[1].subresourceRange.layerCount == 5


def test_the_graphs_plan_is_recorded_through_it():
    mips = ImageDesc(format="VK_FORMAT_R8G8B8A8_UNORM", mips=3)
    g = make(
        ("draw", lambda b: (b.create("x", mips), b.write("x", Access.TRANSFER_WRITE, load=Load.CLEAR))),
        ("read", lambda b: (b.read("x", Access.FRAGMENT_SAMPLED), b.side_effect())),
    )
    (row,) = g.compiled.barriers.before["read"]
    image = vk.ffi.cast("VkImage", 7)
    info = dependency_info(vk, [row], {"x": image}, {}, {"x": vk.VK_IMAGE_ASPECT_COLOR_BIT})
    assert info.imageMemoryBarrierCount == 1 and info.bufferMemoryBarrierCount == 0
    b = info.pImageMemoryBarriers[0]
    assert (b.subresourceRange.baseMipLevel, b.subresourceRange.levelCount) == (0, 3)
    assert (b.oldLayout, b.newLayout) == (
        vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
    )  # fmt: skip
    assert (b.srcStageMask, b.srcAccessMask) == (vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT)
    assert b.dstStageMask == vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT
