"""The deferred form's first rendering: the opaque meshes write what lighting needs per pixel
(a G-buffer) instead of lighting themselves; a compute pass (render/lighting/deferred.py) then lights
every pixel and adds into the HDR colour, and the target's scene rendering (form "deferred",
render/frame/output_passes.py) loads depth and HDR colour for the set-aside rows, billboards and tone map.

Why: on the H100 a fragment shader runs on the few graphics-capable units of the chip, a compute
shader on all of it; thousands of lights cost the forward frame 4x the 6-light one
(docs/performance.md).

Attachments, drawn with dynamic rendering (gbuffer_formats; the output graph's gbuffer pass,
render/passes/deferred_passes.py, begins it and the graph places its barriers):
- depth (reverse-Z), kept for the lighting pass and the scene rendering;
- colour 0, the HDR colour: ambient, emissive and unlit materials (the lighting pass adds the lights);
- colour 1, normal xyz (unit, render-origin space) and roughness, RGBA32F;
- colour 2, base colour rgb (linear, after its texture) and metallic, RGBA16F;
- colour 3, the material index, R32_UINT (NO_MATERIAL, render/layouts.py, where no lit surface
  is: background, unlit materials).
Depth and the HDR colour are the target's (gpu/scene_attachments.py); colours 1-3 are the
output graph's transients, dead after the lighting (the graph may alias them with later images:
weighted transparency's targets).
"""

from __future__ import annotations

from typing import Any

from .pipeline import AttachmentFormats

GBUFFER_FORMAT_NAMES = ("VK_FORMAT_R32G32B32A32_SFLOAT", "VK_FORMAT_R16G16B16A16_SFLOAT", "VK_FORMAT_R32_UINT")
GBUFFER_COLORS = 1 + len(GBUFFER_FORMAT_NAMES)  # the mesh pipelines' colour attachments here


def gbuffer_formats(vk: Any) -> AttachmentFormats:
    """What the G-buffer's pipelines and secondaries are made for: the HDR colour and the three
    G-buffer colours, depth, one sample (the deferred form has no MSAA)."""
    colors = ("VK_FORMAT_R16G16B16A16_SFLOAT", *GBUFFER_FORMAT_NAMES)
    return AttachmentFormats(tuple(getattr(vk, name) for name in colors), vk.VK_FORMAT_D32_SFLOAT, 1)
