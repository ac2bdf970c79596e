"""Steps toward dynamic rendering everywhere: render paths whose pipelines are made
from attachment formats instead of a render pass, and secondaries that inherit the formats of a
vkCmdBeginRendering instead of a render pass and framebuffer. Validation is on: a pipeline or a
secondary that does not match the rendering it is used in fails the test (conftest)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from gpu_context import headless_gpu, shared_device
from host_reads import host_barrier

from ecs_engine.gpu.gbuffer import GBUFFER_FORMAT_NAMES
from ecs_engine.gpu.memory import HOST, Buffer
from ecs_engine.gpu.pipeline import AttachmentFormats
from ecs_engine.gpu.secondary import SecondaryBuffers, end_command_buffer
from ecs_engine.gpu.shadow_maps import shadow_formats
from ecs_engine.render.draw.chunk_paths import InstancedPath, PerEntityPath
from ecs_engine.render.frame.renderer import Renderer
from ecs_engine.render.graph import Access, FrameGraph, ImageDesc, Load, Pass

W, H = 8, 6
BACK = (0.25, 0.5, 1.0, 1.0)
SPOT = (2.0, 0.0, 0.125, 0.5)
RECT = (2, 1, 4, 3)  # x, y, w, h


def test_attachment_formats_give_the_pipeline_fields_of_dynamic_rendering():
    formats = AttachmentFormats(colors=(97, 109), depth=126, samples=4)
    assert formats.spec_kwargs() == dict(
        render_pass=None, subpass=0, color_formats=(97, 109), depth_format=126, samples=4, color_attachments=2
    )
    assert formats == AttachmentFormats((97, 109), 126, 4) and hash(formats) == hash(
        AttachmentFormats((97, 109), 126, 4)
    )


@pytest.mark.parametrize("form", ["hdr", "gbuffer", "shadow"])
def test_render_paths_make_their_pipelines_from_formats(form):
    with headless_gpu() as gpu:
        vk = gpu.device.vk
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        d32 = vk.VK_FORMAT_D32_SFLOAT
        hdr = vk.VK_FORMAT_R16G16B16A16_SFLOAT
        formats = {
            "hdr": AttachmentFormats((hdr,), d32, 1),
            "gbuffer": AttachmentFormats((hdr, *(getattr(vk, n) for n in GBUFFER_FORMAT_NAMES)), d32, 1),
            "shadow": shadow_formats(vk),
        }[form]
        ctx = replace(renderer.path.ctx, formats=formats, gbuffer=form == "gbuffer", shadow=form == "shadow")
        for make in (InstancedPath, PerEntityPath):
            path = make(ctx, "python")
            assert len(path.pipelines) == 2 and all(p is not None for p in path.pipelines)
            path.destroy()
        with pytest.raises(ValueError, match="needs the attachment formats"):
            InstancedPath(replace(ctx, formats=None), "python")


class SecondaryClear(Pass):
    """Clears "hdr" (its load op), then executes a secondary begun with rendering inheritance
    that clears RECT to SPOT."""

    name = "secondary_clear"

    def __init__(self, secondaries: SecondaryBuffers, formats: AttachmentFormats) -> None:
        self.secondaries, self.formats = secondaries, formats

    def setup(self, b):
        b.create("hdr", ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT"))
        b.write("hdr", Access.COLOR_WRITE, load=Load.CLEAR, clear=BACK)

    def record(self, cb, ctx):
        vk = ctx.vk
        secondary = self.secondaries.begin(0, self.secondaries.begin_info_rendering(self.formats))
        x, y, w, h = RECT
        value = vk.VkClearValue(color=vk.VkClearColorValue(float32=list(SPOT)))
        attachment = vk.VkClearAttachment(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, colorAttachment=0, clearValue=value)
        rect = vk.VkClearRect(
            rect=vk.VkRect2D(vk.VkOffset2D(x, y), vk.VkExtent2D(w, h)), baseArrayLayer=0, layerCount=1
        )
        vk.vkCmdClearAttachments(secondary, 1, [attachment], 1, [rect])
        end_command_buffer(vk, secondary)
        ctx.begin_rendering(colors=("hdr",), secondaries=True)
        vk.vkCmdExecuteCommands(cb, 1, [secondary])
        ctx.end_rendering()


class Readback(Pass):
    name = "readback"

    def setup(self, b):
        b.read("hdr", Access.TRANSFER_READ)
        b.write("out", Access.TRANSFER_WRITE)
        b.side_effect()

    def record(self, cb, ctx):
        vk = ctx.vk
        region = vk.VkBufferImageCopy(
            imageSubresource=vk.VkImageSubresourceLayers(
                aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0, baseArrayLayer=0, layerCount=1
            ),
            imageOffset=vk.VkOffset3D(0, 0, 0),
            imageExtent=vk.VkExtent3D(W, H, 1),
        )
        layout = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
        vk.vkCmdCopyImageToBuffer(cb, ctx.image("hdr").handle, layout, ctx.buffer("out").handle, 1, [region])
        host_barrier(vk, cb)


def test_a_secondary_inherits_the_formats_of_the_rendering_it_runs_in():
    device = shared_device()
    vk = device.vk
    secondaries = SecondaryBuffers(device, 1)
    out = Buffer(device, W * H * 4 * 2, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
    graph = FrameGraph(device)
    try:
        formats = AttachmentFormats((vk.VK_FORMAT_R16G16B16A16_SFLOAT,))
        begin = secondaries.begin_info_rendering(formats)
        assert secondaries.begin_info_rendering(AttachmentFormats((vk.VK_FORMAT_R16G16B16A16_SFLOAT,))) is begin
        inherited = vk.ffi.cast("VkCommandBufferInheritanceRenderingInfo*", begin.pInheritanceInfo.pNext)
        assert begin.pInheritanceInfo.renderPass == vk.ffi.NULL
        assert begin.flags == vk.VK_COMMAND_BUFFER_USAGE_RENDER_PASS_CONTINUE_BIT
        assert inherited.colorAttachmentCount == 1 and inherited.pColorAttachmentFormats[0] == formats.colors[0]
        assert inherited.depthAttachmentFormat == 0 and inherited.rasterizationSamples == 1
        graph.import_buffer("out", handle=out.handle, size=out.size)
        graph.add_pass(SecondaryClear(secondaries, formats))
        graph.add_pass(Readback())
        graph.compile((W, H))
        device.submit_once(graph.execute)
        pixels = out.array(np.float16, (H, W, 4)).copy()
    finally:
        graph.destroy()
        out.destroy()
        secondaries.destroy()
    expected = np.empty((H, W, 4), np.float16)
    expected[:] = BACK
    x, y, w, h = RECT
    expected[y : y + h, x : x + w] = SPOT
    np.testing.assert_array_equal(pixels, expected)
