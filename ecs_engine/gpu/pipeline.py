"""Shader modules, pipeline layouts, graphics and compute pipelines (made through the device's one
pipeline cache, see pipeline_cache.py)."""

from __future__ import annotations

import importlib.resources
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import UsageError

if TYPE_CHECKING:
    from .device import Device

# The repo's shaders/ folder installs as the package ecs_engine.shaders (see pyproject.toml).
SHADER_DIR = Path(str(importlib.resources.files("ecs_engine.shaders")))


def shader_path(name: str | Path) -> Path:
    """An engine shader by name ("tonemap.vert": shaders/tonemap.vert.spv), or a game's own
    compiled SPIR-V by its path (a Path, or a str ending in .spv)."""
    own = isinstance(name, Path) or name.endswith(".spv")
    path = Path(name) if own else SHADER_DIR / f"{name}.spv"
    if not path.is_file():
        fix = "compile it with glslc" if own else "run `make shaders`"
        raise UsageError(f"compiled shader {path} is missing: {fix}")
    return path


def shader_module(device: Device, name: str) -> Any:
    vk = device.vk
    code = shader_path(name).read_bytes()
    return vk.vkCreateShaderModule(device.handle, vk.VkShaderModuleCreateInfo(codeSize=len(code), pCode=code), None)


def pipeline_layout(
    device: Device, set_layouts: Sequence[Any], push_constants: Sequence[tuple[int, int, int]] = ()
) -> Any:
    """push_constants: (stage flags, offset, size)."""
    vk = device.vk
    return vk.vkCreatePipelineLayout(
        device.handle,
        vk.VkPipelineLayoutCreateInfo(
            pSetLayouts=list(set_layouts),
            pPushConstantRanges=[vk.VkPushConstantRange(stageFlags=s, offset=o, size=n) for s, o, n in push_constants],
        ),
        None,
    )


@dataclass
class GraphicsPipelineSpec:
    vertex_shader: str
    fragment_shader: str | None  # None: depth only (shadow maps)
    layout: Any
    render_pass: Any  # always None: drawn with dynamic rendering into `color_formats` (and `depth_format`)
    subpass: int = 0  # always 0 (no render pass)
    vertex_stride: int = 0  # 0: no vertex buffer (vertices made in the shader)
    vertex_attributes: list[tuple[int, int, int]] = field(default_factory=list)  # location, format, offset
    cull_back: bool = True
    front_face_ccw: bool = True
    depth_test: bool = True
    depth_write: bool = True
    alpha_blend: bool = False
    fragment_constants: tuple[int, ...] = ()  # uint specialisation constants, constant_id 0, 1, ...
    vertex_constants: tuple[int, ...] = ()  # the vertex shader's, likewise
    polygon_mode: int = 0  # VK_POLYGON_MODE_FILL; LINE (1) and POINT (2) need fillModeNonSolid
    samples: int = 1  # the rendering's MSAA count
    color_attachments: int = 1  # the rendering's; all written alike (the G-buffer has four)
    depth_bias: tuple[float, float] | None = None  # (constant, slope) factors: shadow casters
    depth_or_equal: bool = False  # compare GREATER_OR_EQUAL: the sky, drawn at depth 0 where nothing is
    blend: str = ""  # a BLEND_MODES name ("" with alpha_blend: "alpha")
    color_formats: tuple[int, ...] = ()  # the colour attachments' VkFormats
    depth_format: int = 0  # the depth attachment's VkFormat (0: none)


@dataclass(frozen=True)
class AttachmentFormats:
    """What a pipeline or a secondary drawn with dynamic rendering (vkCmdBeginRendering) must
    know of the attachments instead of a render pass: their VkFormats and MSAA count. A target or
    pass gives one; pipelines made for equal formats are interchangeable."""

    colors: tuple[int, ...] = ()  # the colour attachments' VkFormats, in location order
    depth: int = 0  # the depth attachment's VkFormat (0: none)
    samples: int = 1

    def spec_kwargs(self) -> dict[str, Any]:
        """GraphicsPipelineSpec fields for these attachments (no render pass)."""
        return dict(
            render_pass=None,
            subpass=0,
            color_formats=self.colors,
            depth_format=self.depth,
            samples=self.samples,
            color_attachments=len(self.colors),
        )


# Blend factors per colour attachment (src colour, dst colour, src alpha, dst alpha), the last one
# repeated for further attachments; "" blends nothing. From a table, as pygfx picks its blend modes.
BLEND_MODES: dict[str, tuple[tuple[str, str, str, str], ...]] = {
    "": (),
    "alpha": (("SRC_ALPHA", "ONE_MINUS_SRC_ALPHA", "ONE", "ONE_MINUS_SRC_ALPHA"),),
    # weighted blended order-independent transparency (render/passes/oit.py): premultiplied colour
    # and alpha summed into the accumulation target, the revealage multiplied by (1 - alpha)
    "weighted": (("ONE", "ONE", "ONE", "ONE"), ("ZERO", "ONE_MINUS_SRC_COLOR", "ZERO", "ONE_MINUS_SRC_ALPHA")),
    # its composite: the average colour over the scene, by 1 - revealage (the fragment's alpha)
    "composite": (("ONE_MINUS_SRC_ALPHA", "SRC_ALPHA", "ZERO", "ONE"),),
}


def specialization(vk: Any, values: tuple[int, ...]) -> tuple[Any, Any]:
    """VkSpecializationInfo for uint constants with constant_id 0, 1, ... (None when there are
    none), and the cffi array it points into: keep that alive until the pipeline is made."""
    if not values:
        return None, None
    data = vk.ffi.new("uint32_t[]", [int(v) & 0xFFFFFFFF for v in values])
    entries = [vk.VkSpecializationMapEntry(constantID=i, offset=4 * i, size=4) for i in range(len(values))]
    return vk.VkSpecializationInfo(pMapEntries=entries, dataSize=4 * len(values), pData=data), data


def rendering_info(vk: Any, spec: GraphicsPipelineSpec) -> Any:
    """What a pipeline for dynamic rendering (vkCmdBeginRendering) says instead of a render pass:
    its attachments' formats, as VkPipelineRenderingCreateInfo."""
    if spec.render_pass is not None or spec.subpass:
        raise ValueError("pipelines are made for dynamic rendering: no render pass or subpass")
    if len(spec.color_formats) != spec.color_attachments:
        raise ValueError(
            f"a dynamic-rendering pipeline needs {spec.color_attachments} colour formats, got {len(spec.color_formats)}"
        )
    return vk.VkPipelineRenderingCreateInfo(
        viewMask=0,
        colorAttachmentCount=len(spec.color_formats),
        pColorAttachmentFormats=list(spec.color_formats),
        depthAttachmentFormat=spec.depth_format,
        stencilAttachmentFormat=0,
    )


def graphics_pipeline(device: Device, spec: GraphicsPipelineSpec) -> Any:
    """A pipeline with dynamic viewport and scissor and reverse-Z depth (compare GREATER), for
    dynamic rendering into attachments of `spec.color_formats` and `spec.depth_format`."""
    vk = device.vk
    vert = shader_module(device, spec.vertex_shader)
    frag = shader_module(device, spec.fragment_shader) if spec.fragment_shader else None
    try:
        constants, _constant_data = specialization(vk, spec.fragment_constants)
        vertex_constants, _vertex_data = specialization(vk, spec.vertex_constants)
        stages = [
            vk.VkPipelineShaderStageCreateInfo(
                stage=vk.VK_SHADER_STAGE_VERTEX_BIT, module=vert, pName="main", pSpecializationInfo=vertex_constants
            )
        ]
        if frag is not None:
            stages.append(
                vk.VkPipelineShaderStageCreateInfo(
                    stage=vk.VK_SHADER_STAGE_FRAGMENT_BIT, module=frag, pName="main", pSpecializationInfo=constants
                )
            )
        bias = spec.depth_bias or (0.0, 0.0)
        if spec.vertex_stride:
            vertex_input = vk.VkPipelineVertexInputStateCreateInfo(
                pVertexBindingDescriptions=[
                    vk.VkVertexInputBindingDescription(
                        binding=0, stride=spec.vertex_stride, inputRate=vk.VK_VERTEX_INPUT_RATE_VERTEX
                    )
                ],
                pVertexAttributeDescriptions=[
                    vk.VkVertexInputAttributeDescription(location=loc, binding=0, format=fmt, offset=off)
                    for loc, fmt, off in spec.vertex_attributes
                ],
            )
        else:
            vertex_input = vk.VkPipelineVertexInputStateCreateInfo()
        modes = BLEND_MODES["alpha" if spec.alpha_blend else spec.blend]
        blends = [
            vk.VkPipelineColorBlendAttachmentState(
                blendEnable=vk.VK_TRUE if modes else vk.VK_FALSE,
                srcColorBlendFactor=getattr(vk, f"VK_BLEND_FACTOR_{factors[0]}"),
                dstColorBlendFactor=getattr(vk, f"VK_BLEND_FACTOR_{factors[1]}"),
                colorBlendOp=vk.VK_BLEND_OP_ADD,
                srcAlphaBlendFactor=getattr(vk, f"VK_BLEND_FACTOR_{factors[2]}"),
                dstAlphaBlendFactor=getattr(vk, f"VK_BLEND_FACTOR_{factors[3]}"),
                alphaBlendOp=vk.VK_BLEND_OP_ADD,
                colorWriteMask=0xF,
            )
            for factors in (
                modes[min(k, len(modes) - 1)] if modes else ("ONE", "ZERO", "ONE", "ZERO")
                for k in range(spec.color_attachments)
            )
        ]
        info = vk.VkGraphicsPipelineCreateInfo(
            pNext=rendering_info(vk, spec),
            pStages=stages,
            pVertexInputState=vertex_input,
            pInputAssemblyState=vk.VkPipelineInputAssemblyStateCreateInfo(
                topology=vk.VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST
            ),
            pViewportState=vk.VkPipelineViewportStateCreateInfo(viewportCount=1, scissorCount=1),
            pRasterizationState=vk.VkPipelineRasterizationStateCreateInfo(
                polygonMode=spec.polygon_mode,
                lineWidth=1.0,
                cullMode=vk.VK_CULL_MODE_BACK_BIT if spec.cull_back else vk.VK_CULL_MODE_NONE,
                frontFace=vk.VK_FRONT_FACE_COUNTER_CLOCKWISE if spec.front_face_ccw else vk.VK_FRONT_FACE_CLOCKWISE,
                depthBiasEnable=vk.VK_TRUE if spec.depth_bias else vk.VK_FALSE,
                depthBiasConstantFactor=bias[0],
                depthBiasSlopeFactor=bias[1],
            ),
            pMultisampleState=vk.VkPipelineMultisampleStateCreateInfo(rasterizationSamples=spec.samples),
            pDepthStencilState=vk.VkPipelineDepthStencilStateCreateInfo(
                depthTestEnable=vk.VK_TRUE if spec.depth_test else vk.VK_FALSE,
                depthWriteEnable=vk.VK_TRUE if spec.depth_write else vk.VK_FALSE,
                depthCompareOp=vk.VK_COMPARE_OP_GREATER_OR_EQUAL if spec.depth_or_equal else vk.VK_COMPARE_OP_GREATER,
            ),
            pColorBlendState=vk.VkPipelineColorBlendStateCreateInfo(pAttachments=blends),
            pDynamicState=vk.VkPipelineDynamicStateCreateInfo(
                pDynamicStates=[vk.VK_DYNAMIC_STATE_VIEWPORT, vk.VK_DYNAMIC_STATE_SCISSOR]
            ),
            layout=spec.layout,
            renderPass=vk.ffi.NULL,
            subpass=0,
        )
        device.objects_version += 1
        return vk.vkCreateGraphicsPipelines(device.handle, device.pipeline_cache.handle, 1, [info], None)[0]
    finally:
        vk.vkDestroyShaderModule(device.handle, vert, None)
        if frag is not None:
            vk.vkDestroyShaderModule(device.handle, frag, None)


def compute_pipeline(device: Device, shader: str, layout: Any, constants: tuple[int, ...] = ()) -> Any:
    """`constants`: uint specialisation constants, constant_id 0, 1, ..."""
    vk = device.vk
    module = shader_module(device, shader)
    try:
        info_, _data = specialization(vk, constants)
        stage = vk.VkPipelineShaderStageCreateInfo(
            stage=vk.VK_SHADER_STAGE_COMPUTE_BIT, module=module, pName="main", pSpecializationInfo=info_
        )
        info = vk.VkComputePipelineCreateInfo(stage=stage, layout=layout)
        device.objects_version += 1
        return vk.vkCreateComputePipelines(device.handle, device.pipeline_cache.handle, 1, [info], None)[0]
    finally:
        vk.vkDestroyShaderModule(device.handle, module, None)
