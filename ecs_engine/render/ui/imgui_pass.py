"""Dear ImGui drawn by the engine's Vulkan renderer: imgui-bundle gives Python ImGui, but no
Vulkan renderer, so this is one.

Per frame: the draw lists' vertices and indices are copied (memmove from the addresses the
bindings expose) into this frame slot's mapped buffers; after the tone map, in its dynamic
rendering into the target (so the UI keeps its colours; in the direct form, in a rendering of
its own that loads the target after the scene's), each command is one indexed draw with its
scissor and texture. Either way it draws into the target's colour format alone, so its one
pipeline serves every form of the target.
Textures follow ImGui 1.92's protocol: the backend creates, updates and destroys them as
`ImDrawData.textures` asks, and hands ImGui an id to put in its commands. Images the engine owns
(the editor's shadow map thumbnails) are registered by view (`register_image`: imgui_images.py)
and drawn with `imgui.image(imgui.ImTextureRef(tex_id), size)`.

Vertex colours are sRGB and the render targets are sRGB formats, so the vertex shader decodes
them; textures are sRGB images, decoded by the sampler.
"""

from __future__ import annotations

import ctypes
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ...gpu.array_image import clamped_sampler
from ...gpu.descriptors import write_images
from ...gpu.memory import HOST, Buffer, Image
from ...gpu.pipeline import GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ..layouts import IMGUI_PUSH
from .imgui_images import UserImages
from .imgui_upload import upload_rects

if TYPE_CHECKING:
    from ...gpu.device import Device

VERTEX_BYTES = 20  # ImDrawVert: pos (2 float), uv (2 float), col (RGBA8)
INDEX_BYTES = 4  # imgui-bundle builds ImGui with 32-bit ImDrawIdx
SETS_PER_POOL = 64


@dataclass
class _Texture:
    image: Image
    descriptor_set: Any
    set_array: Any  # VkDescriptorSet[1] for raw calls


@dataclass
class _FrameBuffers:
    vertices: Buffer
    indices: Buffer
    vertex_array: Any  # VkBuffer[1]


@dataclass
class OverlayCounts:
    lists: int = 0
    commands: int = 0
    vertices: int = 0
    indices: int = 0
    images: int = 0  # commands drawing a registered image (register_image)


class ImGuiRenderer:
    def __init__(self, device: Device, target: Any, frames: int) -> None:
        """`target`: the renderer's (offscreen.py, swapchain.py): where the overlay draws."""
        from imgui_bundle import imgui

        self.imgui = imgui
        vk = self.vk = device.vk
        self.device = device
        io = imgui.get_io()
        io.backend_flags |= (
            imgui.BackendFlags_.renderer_has_textures.value | imgui.BackendFlags_.renderer_has_vtx_offset.value
        )
        self.sampler = clamped_sampler(device, max_lod=1.0)
        self.set_layout = vk.vkCreateDescriptorSetLayout(
            device.handle,
            vk.VkDescriptorSetLayoutCreateInfo(
                pBindings=[
                    vk.VkDescriptorSetLayoutBinding(
                        binding=0,
                        descriptorType=vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                        descriptorCount=1,
                        stageFlags=vk.VK_SHADER_STAGE_FRAGMENT_BIT,
                    )
                ]
            ),
            None,
        )
        self._pools: list[Any] = []
        self._free_sets: list[Any] = []
        self.layout = pipeline_layout(device, [self.set_layout], [(vk.VK_SHADER_STAGE_VERTEX_BIT, 0, IMGUI_PUSH.size)])
        self.pipeline = self._pipeline(target)
        self._textures: dict[int, _Texture] = {}
        self._next_id = 1  # 0 means "no texture" to ImGui; user images' ids come from the same count
        self.images = UserImages(vk, device, self._allocate_set, lambda s: self._free_sets.append(s))
        self._frames = [self._frame_buffers(1 << 14, 1 << 15) for _ in range(frames)]
        self._prepared: dict[int, tuple[list[Any], tuple[float, float, float, float]]] = {}
        # the last UI's (ImGui frame, draws, push constants, draw lists, vertex and index counts)
        self._last: tuple[Any, ...] | None = None
        self._copied: dict[int, int] = {}  # per slot: the ImGui frame whose geometry it holds
        self._push = np.zeros(1, dtype=IMGUI_PUSH.dtype)
        self._push_ptr = vk.ffi.from_buffer(self._push)
        self._offsets = vk.ffi.new("VkDeviceSize[1]", [0])
        self._viewport = vk.ffi.new("VkViewport*")
        self.counts = OverlayCounts()
        self.cpu_ms = 0.0  # last frame's prepare + record

    # ---------------------------------------------------------------- buffers
    def _frame_buffers(self, vertices: int, indices: int) -> _FrameBuffers:
        vk = self.vk
        vb = Buffer(self.device, vertices * VERTEX_BYTES, vk.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, HOST)
        ib = Buffer(self.device, indices * INDEX_BYTES, vk.VK_BUFFER_USAGE_INDEX_BUFFER_BIT, HOST)
        return _FrameBuffers(vb, ib, vk.ffi.new("VkBuffer[1]", [vb.handle]))

    def _ensure(self, slot: int, vertices: int, indices: int) -> _FrameBuffers:
        """Grow the slot's buffers (doubling); safe: the slot's fence has been waited on."""
        fb = self._frames[slot]
        fb.indices = fb.indices.grown(indices * INDEX_BYTES)
        vertex_buffer = fb.vertices.grown(vertices * VERTEX_BYTES)
        if vertex_buffer is not fb.vertices:
            fb.vertices, fb.vertex_array = vertex_buffer, self.vk.ffi.new("VkBuffer[1]", [vertex_buffer.handle])
        return fb

    # --------------------------------------------------------------- textures
    def _allocate_set(self) -> Any:
        vk = self.vk
        if not self._free_sets:
            pool = vk.vkCreateDescriptorPool(
                self.device.handle,
                vk.VkDescriptorPoolCreateInfo(
                    maxSets=SETS_PER_POOL,
                    pPoolSizes=[
                        vk.VkDescriptorPoolSize(
                            type=vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, descriptorCount=SETS_PER_POOL
                        )
                    ],
                ),
                None,
            )
            self._pools.append(pool)
            layouts = [self.set_layout] * SETS_PER_POOL
            self._free_sets = list(
                vk.vkAllocateDescriptorSets(
                    self.device.handle,
                    vk.VkDescriptorSetAllocateInfo(
                        descriptorPool=pool, descriptorSetCount=SETS_PER_POOL, pSetLayouts=layouts
                    ),
                )
            )
        return self._free_sets.pop()

    def _create_texture(self, tex: Any) -> None:
        vk = self.vk
        image = Image(
            self.device,
            tex.width,
            tex.height,
            vk.VK_FORMAT_R8G8B8A8_SRGB,
            vk.VK_IMAGE_USAGE_SAMPLED_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT,
            vk.VK_IMAGE_ASPECT_COLOR_BIT,
        )
        descriptor_set = self._allocate_set()
        info = vk.VkDescriptorImageInfo(
            sampler=self.sampler, imageView=image.view, imageLayout=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        )
        write_images(self.device, descriptor_set, 0, [info])
        texture = _Texture(image, descriptor_set, vk.ffi.new("VkDescriptorSet[1]", [descriptor_set]))
        tex_id = self._next_id
        self._next_id += 1
        self._textures[tex_id] = texture
        self._upload(texture, tex, [(0, 0, tex.width, tex.height)], fresh=True)
        tex.set_tex_id(tex_id)
        tex.set_status(self.imgui.ImTextureStatus.ok)

    def register_image(self, view: Any, sampler: Any, layout: int, alive: Callable[[], bool] | None = None) -> int:
        """An ImGui texture id that draws `view` (the caller's, in `layout` whenever the overlay
        draws) through `sampler` (a nearest one shows an image drawn at its on-screen size texel
        for pixel, whatever fraction its corner sits at); `alive()`, when given, is asked every overlay frame: once it
        says False the id is dropped (imgui_images.py)."""
        tex_id = self._next_id
        self._next_id += 1
        self.images.register(tex_id, view, sampler, layout, alive)
        return tex_id

    def update_image(self, tex_id: int, view: Any, sampler: Any, layout: int) -> None:
        """Point `tex_id` at another view (a remade image): the UI built with the id draws on.
        Only after `device.wait_idle()` (its set is rewritten in place)."""
        self.images.update(tex_id, view, sampler, layout)

    def unregister_image(self, tex_id: int) -> None:
        """Stop drawing a registered image (its set is reused once no frame in flight reads it)."""
        self.images.unregister(tex_id)

    def _upload(self, texture: _Texture, tex: Any, rects: list[tuple[int, int, int, int]], fresh: bool) -> None:
        """Copy rectangles of the texture's pixels to the image (imgui_upload.py)."""
        upload_rects(self.device, texture.image.handle, tex, rects, fresh)

    def _destroy_texture(self, tex_id: int) -> None:
        texture = self._textures.pop(tex_id, None)
        if texture is not None:
            texture.image.destroy()
            self._free_sets.append(texture.descriptor_set)

    def update_textures(self, textures: Any, frames_in_flight: int) -> None:
        """Create, update and destroy textures as ImGui asks (ImGui 1.92 texture protocol)."""
        status = self.imgui.ImTextureStatus
        for tex in textures:
            if tex.status == status.want_create:
                self._create_texture(tex)
            elif tex.status == status.want_updates:
                texture = self._textures[int(tex.get_tex_id())]
                rects = [(r.x, r.y, r.w, r.h) for r in tex.updates] or [
                    (tex.update_rect.x, tex.update_rect.y, tex.update_rect.w, tex.update_rect.h)
                ]
                self._upload(texture, tex, [r for r in rects if r[2] > 0 and r[3] > 0], fresh=False)
                tex.set_status(status.ok)
            elif tex.status == status.want_destroy and tex.unused_frames >= frames_in_flight:
                # no frame in flight uses it any more
                self._destroy_texture(int(tex.get_tex_id()))
                tex.set_tex_id(0)
                tex.set_status(status.destroyed)

    # ------------------------------------------------------------------ frame
    def prepare(self, slot: int, frames_in_flight: int) -> None:
        """Textures first, then this frame's geometry (from the last `imgui.render()`) into the
        slot's mapped buffers, and the draws for `record`. Called by the renderer after the slot's
        fence was waited on. When the UI was not rebuilt since (see EditorSession's rate limit),
        the draws are the last ones, and a slot that already holds that geometry copies nothing."""
        t0 = time.perf_counter()
        self.cpu_ms = 0.0
        images_gone = self.images.begin_frame(frames_in_flight)  # the last draws may name them
        draw_data = self.imgui.get_draw_data()
        if draw_data is None or not draw_data.valid:
            self._prepared.pop(slot, None)
            return
        frame = self.imgui.get_frame_count()
        if self._last is None or self._last[0] != frame:
            if draw_data.textures is not None:
                self.update_textures(draw_data.textures, frames_in_flight)
            self._last = (frame, *self._draw_list(draw_data))
        elif images_gone:
            self._last = (frame, *self._draw_list(draw_data))
        _, draws, push, lists, vertices, indices = self._last
        if self._copied.get(slot) != frame:
            fb = self._ensure(slot, max(vertices, 1), max(indices, 1))
            vdst = fb.vertices.bytes().ctypes.data
            idst = fb.indices.bytes().ctypes.data
            vbase = ibase = 0
            for dl in lists:
                nv, ni = dl.vtx_buffer.size(), dl.idx_buffer.size()
                ctypes.memmove(vdst + vbase * VERTEX_BYTES, dl.vtx_buffer.data_address(), nv * VERTEX_BYTES)
                ctypes.memmove(idst + ibase * INDEX_BYTES, dl.idx_buffer.data_address(), ni * INDEX_BYTES)
                vbase += nv
                ibase += ni
            self._copied[slot] = frame
        self._prepared[slot] = (draws, push)
        images = sum(1 for d in draws if d[5]) if len(self.images) else 0
        self.counts = OverlayCounts(len(lists), len(draws), vertices, indices, images)
        self.cpu_ms = (time.perf_counter() - t0) * 1e3

    def _draw_list(self, draw_data: Any) -> tuple[list[Any], tuple[float, ...], list[Any], int, int]:
        """Per command: (VkRect2D* scissor, VkDescriptorSet[1], index count, first index,
        vertex offset, whether it draws a user image), scissors clamped to the display and empty
        ones dropped; made once per UI (and again when a user image goes away)."""
        vk = self.vk
        sx, sy = draw_data.framebuffer_scale.x, draw_data.framebuffer_scale.y
        px, py = draw_data.display_pos.x, draw_data.display_pos.y
        w, h = draw_data.display_size.x * sx, draw_data.display_size.y * sy
        lists = list(draw_data.cmd_lists)
        draws = []
        vbase = ibase = 0
        for dl in lists:
            for cmd in dl.cmd_buffer:
                if cmd.elem_count == 0:
                    continue
                tex_id = int(cmd.get_tex_id())
                texture = self._textures.get(tex_id) or self.images.get(tex_id)
                if texture is None:
                    continue  # an id this backend does not know (or no longer: a dropped image)
                c = cmd.clip_rect
                x0, y0 = max((c.x - px) * sx, 0.0), max((c.y - py) * sy, 0.0)
                x1, y1 = min((c.z - px) * sx, w), min((c.w - py) * sy, h)
                if x1 <= x0 or y1 <= y0:
                    continue
                scissor = vk.ffi.new(
                    "VkRect2D*",
                    {"offset": {"x": int(x0), "y": int(y0)}, "extent": {"width": int(x1 - x0), "height": int(y1 - y0)}},
                )
                draws.append(
                    (
                        scissor,
                        texture.set_array,
                        cmd.elem_count,
                        cmd.idx_offset + ibase,
                        cmd.vtx_offset + vbase,
                        tex_id not in self._textures,
                    )
                )
            vbase += dl.vtx_buffer.size()
            ibase += dl.idx_buffer.size()
        scale = (2.0 / w * sx, 2.0 / h * sy) if w > 0 and h > 0 else (0.0, 0.0)
        push = (scale[0], scale[1], -1.0 - px * scale[0], -1.0 - py * scale[1])
        return draws, push, lists, vbase, ibase

    def record(self, cb: Any, slot: int, width: int, height: int) -> None:
        """Into the primary's overlay rendering (inline): one indexed draw per ImGui
        command."""
        prepared = self._prepared.pop(slot, None)
        if not prepared or not prepared[0]:
            return
        t0 = time.perf_counter()
        draws, push = prepared
        vk = self.vk
        lib = vk.lib
        fb = self._frames[slot]
        graphics = vk.VK_PIPELINE_BIND_POINT_GRAPHICS
        lib.vkCmdBindPipeline(cb, graphics, self.pipeline)
        lib.vkCmdBindVertexBuffers(cb, 0, 1, fb.vertex_array, self._offsets)
        lib.vkCmdBindIndexBuffer(cb, fb.indices.handle, 0, vk.VK_INDEX_TYPE_UINT32)
        vp = self._viewport
        vp.x, vp.y, vp.width, vp.height, vp.minDepth, vp.maxDepth = 0.0, 0.0, float(width), float(height), 0.0, 1.0
        lib.vkCmdSetViewport(cb, 0, 1, vp)
        self._push["scale"], self._push["translate"] = push[:2], push[2:]
        lib.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_VERTEX_BIT, 0, IMGUI_PUSH.size, self._push_ptr)
        bound = None
        layout, null = self.layout, vk.ffi.NULL
        set_scissor, draw = lib.vkCmdSetScissor, lib.vkCmdDrawIndexed
        for scissor, sets, count, first_index, vertex_offset, _ in draws:
            if sets is not bound:
                lib.vkCmdBindDescriptorSets(cb, graphics, layout, 0, 1, sets, 0, null)
                bound = sets
            set_scissor(cb, 0, 1, scissor)
            draw(cb, count, 1, first_index, vertex_offset, 0)
        self.cpu_ms += (time.perf_counter() - t0) * 1e3

    def _pipeline(self, target: Any) -> Any:
        """For dynamic rendering into the target's colour format."""
        vk = self.vk
        return graphics_pipeline(
            self.device,
            GraphicsPipelineSpec(
                "imgui.vert",
                "imgui.frag",
                layout=self.layout,
                render_pass=None,
                color_formats=(target.color_format,),
                vertex_stride=VERTEX_BYTES,
                vertex_attributes=[
                    (0, vk.VK_FORMAT_R32G32_SFLOAT, 0),
                    (1, vk.VK_FORMAT_R32G32_SFLOAT, 8),
                    (2, vk.VK_FORMAT_R8G8B8A8_UNORM, 16),
                ],
                cull_back=False,
                depth_test=False,
                depth_write=False,
                alpha_blend=True,
            ),
        )

    def rebuild(self, target: Any) -> None:
        """The pipeline made again from the shader files (hot reload; the caller waited for the
        device); the old one stays if the new one cannot be made."""
        pipeline = self._pipeline(target)
        old, self.pipeline = self.pipeline, pipeline
        self.vk.vkDestroyPipeline(self.device.handle, old, None)

    def destroy(self) -> None:
        vk = self.vk
        self.device.wait_idle()
        for tex_id in list(self._textures):
            self._destroy_texture(tex_id)
        self.images.clear()  # their sets go with the pools
        for fb in self._frames:
            fb.vertices.destroy()
            fb.indices.destroy()
        for pool in self._pools:
            vk.vkDestroyDescriptorPool(self.device.handle, pool, None)
        vk.vkDestroyPipeline(self.device.handle, self.pipeline, None)
        vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
        vk.vkDestroyDescriptorSetLayout(self.device.handle, self.set_layout, None)
        vk.vkDestroySampler(self.device.handle, self.sampler, None)
        # ImGui may still hold ids of the textures just destroyed: mark them so
        io_textures = self.imgui.get_platform_io().textures
        for tex in io_textures:
            if tex.status != self.imgui.ImTextureStatus.destroyed:
                tex.set_tex_id(0)
                tex.set_status(self.imgui.ImTextureStatus.destroyed)
