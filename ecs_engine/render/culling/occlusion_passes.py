"""Two-phase occlusion culling for the indirect mode (`--culling occlusion`: culling/occlusion.py's
method asks for these passes), after zeux/niagara.

Per frame, in the primary before the scene's render pass, each step one of the frame graph's
passes (render/draw/cull_pass.py, recording render/draw/indirect_compute.py's steps), which
declare their accesses: the graph places the barriers between them:
1. early cull (cull_early.comp): the rows the last frame found visible, still in the frustum,
   with an opaque one-sided material; compact.comp makes their draws;
2. their depth alone, into this module's depth image (the target's samples; dynamic rendering
   with the shadow maps' depth format, begun by the graph; no bias;
   shadow_indirect.vert through the camera's set 0: the same position arithmetic as
   mesh_indirect.vert);
3. the depth pyramid (depth_reduce.comp): level k holds, per texel, the farthest depth of the
   2^(k+1)-pixel square it covers, in a storage buffer;
4. late cull (cull_late.comp): every row against the frustum and then its sphere's screen rect
   against the pyramid; the survivors are the frame's draws, and their verdict is the next
   frame's early set.

Unlike niagara, the early rows are drawn again in the scene pass instead of into it: the scene's
render pass (forward, deferred, HDR and MSAA forms, render/frame/renderer.py) stays one pass, and the
early pass costs their vertices alone. What is visible in the final image lies in front of the
early depth on a pixel it covers (every early row passes the late test and is drawn), so the
late test keeps it: the image is frustum culling's. With one sample per pixel a row that covers
no pixel centre is culled too (sub-pixel culling): it could not have produced a fragment. With
MSAA the early depth has the target's samples and the pyramid's first level takes the farthest
of them; rows are tested over every pixel they touch, and sub-pixel culling is off (samples lie
off the centres). Wireframe and points show what is behind them: those frames cull the frustum
alone (culling/occlusion.py's `can_cull`).

The images, buffers and pipelines are shared by the frames in flight: the GPU runs frames in
submission order and each frame's barriers order its writes after the last frame's reads.
"""

from __future__ import annotations

from typing import Any

from ...gpu.array_image import nearest_sampler
from ...gpu.barrier import Barrier
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_buffers, write_images
from ...gpu.memory import DEVICE, Buffer, Image
from ...gpu.owned import Owned
from ...gpu.pipeline import GraphicsPipelineSpec, compute_pipeline, graphics_pipeline, pipeline_layout
from ...gpu.shadow_maps import READ_LAYOUT_NAME, SHADOW_FORMAT_NAME, shadow_formats
from ..draw.chunk_paths import vertex_attributes
from ..draw.path import PathContext
from ..layouts import (
    BINDING_EARLY_DEPTH,
    BINDING_PYRAMID,
    BINDING_VISIBILITY,
    CULL_PUSH,
    MESH_VERTEX,
    REDUCE_GROUP,
    REDUCE_PUSH,
    UINT_BYTES,
)

#: the frame graph's names of the imports (cull_pass.py's passes declare them)
DEPTH, PYRAMID, VISIBILITY = "occlusion.depth", "occlusion.pyramid", "occlusion.visibility"


def pyramid_levels(width: int, height: int) -> list[tuple[int, int, int]]:
    """(first float, width, height) of each level: halved, rounded up, down to one texel."""
    levels, first = [], 0
    w, h = width, height
    while True:
        w, h = (w + 1) // 2, (h + 1) // 2
        levels.append((first, w, h))
        first += w * h
        if w == 1 and h == 1:
            return levels


class OcclusionPasses:
    """The early depth, the pyramid, last frame's visibility per row, and their passes."""

    def __init__(self, ctx: PathContext, sets: list[Any], graphics_layout: Any) -> None:
        """`sets`: the cull passes' sets 0 and 1 (their layouts); `graphics_layout`: the
        indirect draws' pipeline layout (sets 0 and 1), which the early depth draws share."""
        self.ctx = ctx
        vk = ctx.device.vk
        self.vk = vk
        self.size = (0, 0)
        self.levels: list[tuple[int, int, int]] = []
        self.depth: Image | None = None
        self.pyramid: Buffer | None = None
        self.visibility: Buffer | None = None
        self.fresh = False  # the visibility buffer is new: zero it before the first early pass
        self.samples = ctx.samples  # the target's MSAA count: the early depth's too
        # the passes' objects and the visibility; the depth image and pyramid, made again at
        # each new size, in a scope of their own
        self.owned = Owned(ctx.device)
        self._sized = Owned(ctx.device)
        try:
            self._build(ctx, sets, graphics_layout)
        except BaseException:
            self.destroy()  # what was made so far
            raise

    def _build(self, ctx: PathContext, sets: list[Any], graphics_layout: Any) -> None:
        device, vk = ctx.device, self.vk
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        sampled = vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
        compute = vk.VK_SHADER_STAGE_COMPUTE_BIT
        owned, handle = self.owned, device.handle

        def pipeline(made: Any) -> Any:
            return owned.add(made, lambda: vk.vkDestroyPipeline(handle, made, None))

        self.set_layout = owned.add(
            DescriptorSetLayout(
                device,
                [
                    (BINDING_VISIBILITY, ssbo, compute),
                    (BINDING_PYRAMID, ssbo, compute),
                    (BINDING_EARLY_DEPTH, sampled, compute),
                ],
            )
        )
        self.pool = owned.add(DescriptorPool(device, 1, {ssbo: 2, sampled: 1}))
        self.set = self.pool.allocate(self.set_layout)
        layout = self.layout = pipeline_layout(device, [*sets, self.set_layout.handle], [(compute, 0, CULL_PUSH.size)])
        owned.add(layout, lambda: vk.vkDestroyPipelineLayout(handle, layout, None))
        self.early = pipeline(compute_pipeline(device, "cull_early.comp", layout))
        self.late = pipeline(compute_pipeline(device, "cull_late.comp", layout))
        reduce = "depth_reduce_ms.comp" if self.samples > 1 else "depth_reduce.comp"
        self.reduce = pipeline(compute_pipeline(device, reduce, layout))
        base = dict(
            layout=graphics_layout,
            vertex_stride=MESH_VERTEX.itemsize,
            vertex_attributes=vertex_attributes(vk, ("position",)),
            vertex_constants=(ctx.material_features,),  # deform.glsl's (FEATURE_DEFORM)
            **shadow_formats(vk, self.samples).spec_kwargs(),  # depth alone, drawn with dynamic rendering
        )
        plain = pipeline(graphics_pipeline(device, GraphicsPipelineSpec("shadow_indirect.vert", None, **base)))
        mirrored = GraphicsPipelineSpec("shadow_indirect.vert", None, front_face_ccw=False, **base)
        self.pipelines: tuple[Any, ...] = (plain, pipeline(graphics_pipeline(device, mirrored)))
        sampler = self.sampler = nearest_sampler(device)
        owned.add(sampler, lambda: vk.vkDestroySampler(handle, sampler, None))
        self._reduce_push = vk.ffi.new("uint32_t[8]")
        self._set_array = vk.ffi.new("VkDescriptorSet[1]", [self.set])
        compute = vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
        rw = vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT
        self._level_barrier = Barrier(vk, compute, compute, vk.VK_ACCESS_SHADER_WRITE_BIT, rw)

    # ------------------------------------------------------------ resources
    def ensure(self, width: int, height: int, rows: int) -> None:
        """The depth image and pyramid at the target's size, the visibility for `rows` rows.
        Growing waits for the device: the frames in flight share them (sizes change rarely)."""
        vk, device = self.vk, self.ctx.device
        grow_rows = self.visibility is None or self.visibility.size < UINT_BYTES * max(rows, 1)
        if (width, height) == self.size and not grow_rows:
            return
        device.wait_idle()
        if grow_rows:
            usage = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
            bigger = Buffer(device, UINT_BYTES * max(rows + rows // 2, 1024), usage, DEVICE)  # may fail: keep the old
            if self.visibility is not None:
                self.owned.release(self.visibility)
            self.visibility, self.fresh = self.owned.add(bigger), True
        if (width, height) != self.size:
            self._release_images()
            self.depth = self._sized.add(
                Image(
                    device,
                    width,
                    height,
                    getattr(vk, SHADOW_FORMAT_NAME),
                    vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT,
                    vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                    samples=self.samples,
                )
            )
            self.levels = pyramid_levels(width, height)
            first, w, h = self.levels[-1]
            usage = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
            self.pyramid = self._sized.add(Buffer(device, 4 * (first + w * h), usage, DEVICE))
            self.size = (width, height)
        assert self.visibility is not None and self.pyramid is not None and self.depth is not None
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        write_buffers(
            device, self.set, [(BINDING_VISIBILITY, ssbo, self.visibility), (BINDING_PYRAMID, ssbo, self.pyramid)]
        )
        layout = getattr(vk, READ_LAYOUT_NAME)  # the graph's DEPTH_SAMPLED (the pyramid pass reads it so)
        depth = vk.VkDescriptorImageInfo(sampler=self.sampler, imageView=self.depth.view, imageLayout=layout)
        write_images(device, self.set, BINDING_EARLY_DEPTH, [depth])

    # ---------------------------------------------------------------- record
    def bind(self, cb: Any) -> None:
        """Set 2, after the cull passes' sets 0 and 1."""
        vk = self.vk
        vk.lib.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.layout, 2, 1, self._set_array, 0, vk.ffi.NULL
        )

    def zero_visibility(self, cb: Any) -> None:
        """A new visibility buffer says "not visible" everywhere (the pass that does it declares
        the write while `fresh`: the graph places the barrier to the early cull)."""
        if self.fresh and self.visibility is not None:
            self.vk.lib.vkCmdFillBuffer(cb, self.visibility.handle, 0, self.visibility.size, 0)
            self.fresh = False

    def record_pyramid(self, cb: Any) -> None:
        """Every level, each after the one below it: the levels share one storage buffer (the
        graph's "occlusion.pyramid"), so the barrier between two levels' dispatches is this
        pass's own (the graph tracks mips of images, not ranges of a buffer)."""
        vk = self.vk
        lib = vk.lib
        lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_COMPUTE, self.reduce)
        push = self._reduce_push
        source = (self.size[0], self.size[1], 0, self.samples)  # level 0 reads the depth image
        for k, (first, w, h) in enumerate(self.levels):
            if k:
                self._level_barrier.record(lib, cb)
            push[0:8] = [*source, w, h, first, 0]
            lib.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_COMPUTE_BIT, 0, REDUCE_PUSH.size, push)
            lib.vkCmdDispatch(cb, -(-w // REDUCE_GROUP), -(-h // REDUCE_GROUP), 1)
            source = (w, h, first, 0)

    # ------------------------------------------------------------ the graph
    def import_into(self, graph: Any) -> None:
        """The depth image, the pyramid and the visibility as the frame graph's imports (shared by
        the frames in flight: each frame's first use waits for the frame before's, in compute).
        The depth's contents do not outlive the frame (UNDEFINED before and after); the
        visibility carries the last frame's verdict to this frame's early cull."""
        assert self.depth is not None and self.pyramid is not None and self.visibility is not None
        token = self.depth_token
        if not graph.reuse_import(DEPTH, token):
            graph.import_image(
                DEPTH,
                handle=self.depth.handle,
                view=self.depth.view,
                format=SHADOW_FORMAT_NAME,
                extent=self.size,
                samples=self.samples,
                layout_before="VK_IMAGE_LAYOUT_UNDEFINED",
                layout_after="VK_IMAGE_LAYOUT_UNDEFINED",
                stage_before="COMPUTE_SHADER",  # the frame before's pyramid read it
                token=token,
            )
        for name, buffer in ((PYRAMID, self.pyramid), (VISIBILITY, self.visibility)):
            token = (id(buffer), buffer.handle, buffer.size)
            if not graph.reuse_import(name, token):
                size = buffer.size
                graph.import_buffer(name, handle=buffer.handle, size=size, stage_before="COMPUTE_SHADER", token=token)

    @property
    def depth_token(self) -> tuple:
        """What the depth's import and rendering are made from."""
        assert self.depth is not None
        return (id(self.depth), self.depth.handle, self.size, self.samples)

    def imports(self) -> tuple:
        """The imports' identities (equal: import_into imports the same)."""
        assert self.pyramid is not None and self.visibility is not None
        buffers = (self.pyramid, self.visibility)
        return (self.depth_token, *((id(b), b.handle, b.size) for b in buffers))

    def destroy(self) -> None:
        """Also when half built (the constructor failed): what exists goes."""
        self._release_images()
        self.owned.destroy()
        self.visibility = None

    def _release_images(self) -> None:
        self._sized.destroy()
        self.depth = self.pyramid = None
        self.size = (0, 0)
