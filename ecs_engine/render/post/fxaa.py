"""FXAA: fast approximate anti-aliasing (Timothy Lottes, NVIDIA, FXAA 3.11, PC quality), a
full-screen pass on the tone-mapped, display-referred image, before the UI; added to a frame
graph with one call, `add_fxaa(graph, FxaaSettings(), source="ldr", target="target")`.

It finds edges in the finished image and blends across them, so it smooths what MSAA misses
(alpha-tested foliage, shading and specular aliasing) at the cost of one full-screen pass and
some softening of texture detail. Per pixel (shaders/fxaa.frag):

1. **Luma** of the colour, Rec. 601 weights (0.299, 0.587, 0.114) on the display-encoded value
   (perceptual, as FXAA's thresholds assume); for an _SRGB source, which sampling decodes to
   linear, the square root of the linear luma. No luma in alpha is needed.
2. **Early exit**: the range of the luma over the pixel and its four neighbours below
   max(edge_threshold_min, edge_threshold x the brightest) means no edge: the pixel is written
   back exactly as read (flat and dark regions cost 5 texel reads).
3. **Sub-pixel amount**: how far the centre's luma stands from the 3x3 low-pass (1-2-1 weights,
   /12), by the range, through a smoothstep, squared, times `subpix`.
4. **Orientation**: horizontal if the second differences across rows (3 columns, the centre's
   weighted twice) are at least those across columns; the pixel pairs with the neighbour across
   the edge with the larger luma step.
5. **End search**: from the point half-way to that neighbour, walk along the edge both ways by
   the preset's steps, reading bilinear samples (which average the pair's two rows), until the
   luma leaves the pair's mean by a quarter of the gradient. Preset 39 ("extreme quality, no
   dither"): 12 steps of 1, 1, 1, 1, 1, 1.5, 2, 2, 2, 2, 4, 8 texels (`QUALITY_STEPS`), so an
   edge up to 26 texels long each way is traced texel by texel for its first 5.
6. **Blend**: if the nearer end turns the right way (the luma there and the centre lie on
   opposite sides of the pair's mean), offset the final sample towards the neighbour by
   0.5 - (distance to the nearer end) / (span length) of a texel; at least by the sub-pixel
   amount. One bilinear read at the offset position is the output; alpha is the centre's.

The texel reads of steps 1-4 are texelFetch, clamped to the edge; the search and the blend read
through a bilinear, clamp-to-edge sampler at LOD 0. tests/fxaa_reference.py is the same
algorithm in NumPy (float64), and tests/test_fxaa.py compares the GPU's result with it.

Settings (FXAA 3.11's defaults): `subpix` 0.75 (1 softer, 0 off), `edge_threshold` 0.166 (0.125
high quality, 0.333 too little), `edge_threshold_min` 0.0833 (0.0312 visible limit).
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import UsageError
from ...gpu.array_image import clamped_sampler
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_set
from ...gpu.owned import Owned
from ...gpu.pipeline import pipeline_layout, shader_module
from ..graph import Access, ImageDesc, Pass
from ..graph.resources import format_name

__all__ = ["PRESET", "QUALITY_STEPS", "FxaaPass", "FxaaSettings", "add_fxaa", "fullscreen_pipeline"]

PRESET = 39
QUALITY_STEPS = (1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0)  # shaders/fxaa.frag's STEP
LUMA_WEIGHTS = (0.299, 0.587, 0.114)
_PUSH_BYTES = 24  # float subpix, edge_threshold, edge_threshold_min (+ padding), ivec2 offset
_SETS = 8  # descriptor sets kept, one per source view seen


@dataclass(frozen=True)
class FxaaSettings:
    """FXAA 3.11's three knobs, its defaults; each a number in [0, 1] (a NaN, a bool or one
    outside is a UsageError naming it)."""

    subpix: float = 0.75
    edge_threshold: float = 0.166
    edge_threshold_min: float = 0.0833

    def __post_init__(self) -> None:
        for name in ("subpix", "edge_threshold", "edge_threshold_min"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise UsageError(f"FXAA {name} must be a number in [0, 1], got {value!r}")
            if not 0.0 <= value <= 1.0:
                raise UsageError(f"FXAA {name} must be in [0, 1], got {value!r}")

    def push(self) -> np.ndarray:
        """The shader's push constants."""
        return np.array([self.subpix, self.edge_threshold, self.edge_threshold_min, 0.0], np.float32)


def is_linear_source(fmt: str) -> bool:
    """An _SRGB image is sampled as linear colour; its luma is then square-rooted."""
    return fmt.removeprefix("VK_FORMAT_").endswith("_SRGB")


def fullscreen_pipeline(device: Any, layout: Any, fragment_shader: str, color_format: int, constants: Any) -> Any:
    """A pipeline drawing the full-screen triangle of shaders/tonemap.vert (3 vertices, no
    vertex buffer) with `fragment_shader`, for dynamic rendering into one colour attachment of
    `color_format` (VkPipelineRenderingCreateInfo, no render pass); no depth, no blending,
    dynamic viewport and scissor. `constants`: the fragment stage's VkSpecializationInfo or None."""
    vk = device.vk
    vert = shader_module(device, "tonemap.vert")
    frag = None
    try:
        frag = shader_module(device, fragment_shader)
        stages = [
            vk.VkPipelineShaderStageCreateInfo(stage=vk.VK_SHADER_STAGE_VERTEX_BIT, module=vert, pName="main"),
            vk.VkPipelineShaderStageCreateInfo(
                stage=vk.VK_SHADER_STAGE_FRAGMENT_BIT, module=frag, pName="main", pSpecializationInfo=constants
            ),
        ]
        rendering = vk.VkPipelineRenderingCreateInfo(colorAttachmentCount=1, pColorAttachmentFormats=[color_format])
        blend = vk.VkPipelineColorBlendAttachmentState(blendEnable=vk.VK_FALSE, colorWriteMask=0xF)
        info = vk.VkGraphicsPipelineCreateInfo(
            pNext=rendering,
            pStages=stages,
            pVertexInputState=vk.VkPipelineVertexInputStateCreateInfo(),
            pInputAssemblyState=vk.VkPipelineInputAssemblyStateCreateInfo(
                topology=vk.VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST
            ),
            pViewportState=vk.VkPipelineViewportStateCreateInfo(viewportCount=1, scissorCount=1),
            pRasterizationState=vk.VkPipelineRasterizationStateCreateInfo(
                polygonMode=vk.VK_POLYGON_MODE_FILL, cullMode=vk.VK_CULL_MODE_NONE, lineWidth=1.0
            ),
            pMultisampleState=vk.VkPipelineMultisampleStateCreateInfo(rasterizationSamples=vk.VK_SAMPLE_COUNT_1_BIT),
            pColorBlendState=vk.VkPipelineColorBlendStateCreateInfo(pAttachments=[blend]),
            pDynamicState=vk.VkPipelineDynamicStateCreateInfo(
                pDynamicStates=[vk.VK_DYNAMIC_STATE_VIEWPORT, vk.VK_DYNAMIC_STATE_SCISSOR]
            ),
            layout=layout,
            renderPass=None,
            subpass=0,
        )
        device.objects_version += 1
        return vk.vkCreateGraphicsPipelines(device.handle, device.pipeline_cache.handle, 1, [info], None)[0]
    finally:
        vk.vkDestroyShaderModule(device.handle, vert, None)
        if frag is not None:
            vk.vkDestroyShaderModule(device.handle, frag, None)


class FxaaPass(Pass):
    """Reads `source` (sampled in the fragment shader) and writes `target` (a colour attachment,
    every pixel: its old contents are discarded) of the same size. With `create`, the pass makes
    `target` as a transient of that description (a test's, an editor viewport's); otherwise the
    graph has it already (the window). Its GPU objects are made on the first record."""

    def __init__(
        self,
        settings: FxaaSettings | None = None,
        source: str = "ldr",
        target: str = "target",
        *,
        create: ImageDesc | None = None,
        name: str = "fxaa",
    ) -> None:
        settings = FxaaSettings() if settings is None else settings
        if not isinstance(settings, FxaaSettings):
            raise UsageError(f"FXAA settings must be FxaaSettings, got {settings!r}")
        if source == target:
            raise UsageError(f"FXAA reads {source!r} and cannot write the image it reads")
        self.name, self.settings, self.source, self.target, self.create = name, settings, source, target, create
        self._push = np.zeros(1, [("settings", np.float32, (4,)), ("offset", np.int32, (2,))])
        self._push["settings"][0] = settings.push()
        # where it writes the target: None, the whole target (the source's size); else a
        # callable giving (x, y, width, height), a camera view's rectangle of the window
        # (render/frame/view_graph.py), the source drawn from its corner; the rest is kept
        self.place: Any = None
        self._owned: Owned | None = None
        self._set_layout: Any = None
        self._layout: Any = None
        self._sampler: Any = None
        self._pool: DescriptorPool | None = None
        self._sets: dict[tuple[int, int], Any] = {}  # source (image, view) handle values -> VkDescriptorSet[1]
        self._generation: object = None  # what the sets were made for (see _set_for)
        self.graph: Any = None  # the graph it is in (add_fxaa sets it): its compiles date the sets
        self._pipelines: dict[tuple[int, bool], Any] = {}  # (target format, linear source) -> pipeline

    def setup(self, builder: Any) -> None:
        if self.create is not None:
            builder.create(self.target, self.create)
        builder.read(self.source, Access.FRAGMENT_SAMPLED)
        builder.write(self.target, Access.COLOR_WRITE, region=self.place is not None)

    def key(self) -> Hashable:
        return (self.settings,) if self.place is None else (self.settings, self.place())

    def declares(self) -> Hashable:
        return self.place is not None  # its setup reads what it was made with, and whether it is placed

    def record(self, cb: Any, ctx: Any) -> None:
        vk = ctx.vk
        lib = vk.lib
        source, target = ctx.image(self.source), ctx.image(self.target)
        area = None if self.place is None else tuple(self.place())
        into = tuple(target.extent) if area is None else area[2:]
        if tuple(source.extent) != into:
            raise UsageError(
                f"FXAA reads {self.source!r} ({source.extent[0]}x{source.extent[1]}) into {self.target!r} "
                f"({into[0]}x{into[1]}): they must be the same size"
            )
        if source.samples != 1 or target.samples != 1:
            raise UsageError(f"FXAA reads and writes single-sampled images: resolve {self.source!r} first")
        if self._owned is None:
            self._make(ctx.device)
        linear = is_linear_source(format_name(vk, source.format))
        pipeline = self._pipeline(ctx.device, int(target.format), linear)
        descriptor_set = self._set_for(ctx.device, source)
        ctx.begin_rendering(colors=(self.target,), area=area)
        self._push["offset"][0] = (0, 0) if area is None else area[:2]
        point = vk.VK_PIPELINE_BIND_POINT_GRAPHICS
        lib.vkCmdBindPipeline(cb, point, pipeline)
        lib.vkCmdBindDescriptorSets(cb, point, self._layout, 0, 1, descriptor_set, 0, vk.ffi.NULL)
        stage = vk.VK_SHADER_STAGE_FRAGMENT_BIT
        lib.vkCmdPushConstants(cb, self._layout, stage, 0, _PUSH_BYTES, vk.ffi.from_buffer(self._push))
        lib.vkCmdDraw(cb, 3, 1, 0, 0)
        ctx.end_rendering()

    def _make(self, device: Any) -> None:
        vk = device.vk
        owned = Owned(device)
        try:
            stage = vk.VK_SHADER_STAGE_FRAGMENT_BIT
            self._set_layout = owned.add(
                DescriptorSetLayout(device, [(0, vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, stage)])
            )
            layout = pipeline_layout(device, [self._set_layout.handle], [(stage, 0, _PUSH_BYTES)])
            self._layout = owned.add(layout, lambda: vk.vkDestroyPipelineLayout(device.handle, layout, None))
            sampler = clamped_sampler(device, max_lod=0.0)  # bilinear, clamp to edge, LOD 0
            self._sampler = owned.add(sampler, lambda: vk.vkDestroySampler(device.handle, sampler, None))
        except BaseException:
            owned.destroy()
            raise
        self._owned = owned

    def _pipeline(self, device: Any, color_format: int, linear: bool) -> Any:
        found = self._pipelines.get((color_format, linear))
        if found is not None:
            return found
        vk = device.vk
        data = vk.ffi.new("uint32_t[]", [1 if linear else 0])
        constants = vk.VkSpecializationInfo(
            pMapEntries=[vk.VkSpecializationMapEntry(constantID=0, offset=0, size=4)], dataSize=4, pData=data
        )
        pipeline = fullscreen_pipeline(device, self._layout, "fxaa.frag", color_format, constants)
        assert self._owned is not None
        self._owned.add(pipeline, lambda: vk.vkDestroyPipeline(device.handle, pipeline, None))
        self._pipelines[(color_format, linear)] = pipeline
        return pipeline

    def _set_for(self, device: Any, source: Any) -> Any:
        """The set naming the source's view, written once (never rewritten: a command buffer
        recorded with it, a replayed frame or one in flight, stays valid). The sets are kept per
        (image, view) handle values within one compile of the graph: a compile makes new
        transients, whose handles may reuse the values of destroyed ones, so the sets made so
        far go then. Without the graph known (a pass added by hand), a new source image object
        counts as a new compile (right for a transient source; an imported one is a new object
        each frame, so import sources through add_fxaa). An importer that remakes its source
        image without the graph compiling again calls forget_views()."""
        vk = device.vk
        assert self._owned is not None
        if self.graph is not None:
            generation: object = self.graph.compiles
            changed = generation != self._generation
        else:
            generation = source
            changed = source is not self._generation
        if changed:
            if self._sets:
                device.wait_idle()
            self.forget_views()
            self._generation = generation
        key = (int(vk.ffi.cast("uintptr_t", source.handle)), int(vk.ffi.cast("uintptr_t", source.view)))
        found = self._sets.get(key)
        if found is not None:
            return found
        if self._pool is None or len(self._sets) >= _SETS:
            if self._sets:
                device.wait_idle()  # the old sets may be bound by frames in flight
            self.forget_views()
            pool = DescriptorPool(device, _SETS, {vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: _SETS})
            self._pool = self._owned.add(pool)
        descriptor_set = self._pool.allocate(self._set_layout)
        layout = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        write_set(device, descriptor_set, samplers=[(0, self._sampler, source.view, layout)])
        found = self._sets[key] = vk.ffi.new("VkDescriptorSet[1]", [descriptor_set])
        return found

    def forget_views(self) -> None:
        """Drop every descriptor set (call it with the GPU idle, when views they name go)."""
        if self._pool is not None and self._owned is not None:
            self._owned.release(self._pool)
        self._pool = None
        self._sets.clear()

    def destroy(self) -> None:
        """Its pipelines, sampler, layouts and sets (idempotent)."""
        if self._owned is not None:
            self._owned.destroy()
        self._owned = self._pool = None
        self._sets.clear()
        self._pipelines.clear()
        self._generation = None


def add_fxaa(
    graph: Any,
    settings: FxaaSettings | None = None,
    source: str = "ldr",
    target: str = "target",
    *,
    create: ImageDesc | None = None,
    before: str | None = None,
) -> FxaaPass:
    """Add FXAA from the tone-mapped image `source` into `target` (after the passes added so
    far, or just before the pass named `before`: the UI); the pass it added. The graph
    destroys it with `graph.destroy()`."""
    p = FxaaPass(settings, source, target, create=create)
    p.graph = graph
    if before is None:
        graph.add_pass(p)
    else:
        graph.add_pass(p, before=before)
    return p
