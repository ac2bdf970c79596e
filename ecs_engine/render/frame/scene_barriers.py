"""The barriers the scene's render passes did by their layouts and external subpass
dependencies, now that those passes draw with dynamic rendering (vkCmdBeginRendering): each pass
gets a `before` and an `after` gpu/rendering.py Dependency with the stages, accesses and layout
transitions its render pass had, so nothing the passes' readers see changes. Kept in one place
for the renderer's frame graph to take over (it derives them from the passes' declared accesses).

- the G-buffer pass (gpu/gbuffer.py): every attachment cleared from UNDEFINED once the previous
  frame's lighting, forward pass and tone map are done with them (frames in flight share them);
  after, depth DEPTH_STENCIL_READ_ONLY (the lighting samples it) and the colours GENERAL (storage
  images), the writes visible to the lighting's compute reads and writes;
- weighted transparency's accumulation (oit_pass.py): its two targets cleared from UNDEFINED,
  depth (read-only, as the lighting left it) tested once the G-buffer's writes are visible; after,
  the targets SHADER_READ_ONLY for the composite's fragment reads;
(the scene's rendering in each form is the output graph's forward pass, render/passes/forward.py:
the graph places its barriers).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ...gpu.rendering import Dependency


def _stages(vk: Any) -> tuple[int, int, int, int]:
    """(colour output, fragment tests, fragment shader, compute shader) stage bits."""
    tests = vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT
    return (
        vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
        tests,
        vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
        vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
    )


def gbuffer_barriers(vk: Any, depth: Any, colors: Sequence[Any]) -> tuple[Dependency, Dependency]:
    """(before, after) the G-buffer rendering; `depth` and `colors` (HDR colour, then the
    G-buffer's) are VkImages."""
    color_stage, tests, fragment, compute = _stages(vk)
    color_write = vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT
    depth_write = vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
    color_rw = color_write | vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT
    depth_rw = depth_write | vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT
    undefined, general = vk.VK_IMAGE_LAYOUT_UNDEFINED, vk.VK_IMAGE_LAYOUT_GENERAL
    color_layout = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    depth_layout = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL
    color_aspect, depth_aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT, vk.VK_IMAGE_ASPECT_DEPTH_BIT
    before = Dependency(
        vk,
        (color_stage | tests | compute | fragment, color_write | depth_write | vk.VK_ACCESS_2_SHADER_WRITE_BIT),
        (color_stage | tests, color_rw | depth_rw),
        [(depth, depth_aspect, undefined, depth_layout)]
        + [(image, color_aspect, undefined, color_layout) for image in colors],
    )
    after = Dependency(
        vk,
        (color_stage | tests, color_write | depth_write),
        (compute, vk.VK_ACCESS_2_SHADER_READ_BIT | vk.VK_ACCESS_2_SHADER_WRITE_BIT),
        [(depth, depth_aspect, depth_layout, vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL)]
        + [(image, color_aspect, color_layout, general) for image in colors],
    )
    return before, after


def oit_barriers(vk: Any, targets: Sequence[Any], depth: Any) -> tuple[Dependency, Dependency]:
    """(before, after) weighted transparency's accumulation; `targets` (accumulation,
    revealage) and `depth` are VkImages."""
    color_stage, tests, fragment, compute = _stages(vk)
    color_aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT
    color_layout = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    depth_read = vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL
    before = Dependency(
        vk,
        (tests | compute | fragment, vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT),
        (
            tests | color_stage,
            vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
        ),
        [(image, color_aspect, vk.VK_IMAGE_LAYOUT_UNDEFINED, color_layout) for image in targets]
        + [(depth, vk.VK_IMAGE_ASPECT_DEPTH_BIT, depth_read, depth_read)],
    )
    after = Dependency(
        vk,
        (color_stage, vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT),
        (fragment, vk.VK_ACCESS_2_SHADER_READ_BIT),
        [(image, color_aspect, color_layout, vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL) for image in targets],
    )
    return before, after
