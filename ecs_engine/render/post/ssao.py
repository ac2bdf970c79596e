"""Screen-space ambient occlusion as frame-graph passes: GTAO, the horizon-based method of
Jimenez et al. ("Practical Real-Time Strategies for Accurate Indirect Occlusion", 2016), as
Intel's XeGTAO and Bevy's bevy_pbr/src/ssao implement it.

Why GTAO and not a hemisphere of random samples: its visibility is an analytic integral of the
cosine-weighted arc between the two horizons of each screen slice, so a few slices of a few
samples give the value a hemisphere needs dozens of samples for, it is unbiased against a
"ground truth" ray-traced AO by design (a flat plane gets 1, not a darkened grey), and it is
what Bevy ships, so its settings and look carry over.

Passes (ssao_passes.py; shaders/ssao_*.comp):
1. gtao: depth ("depth", D32_SFLOAT reverse-Z, sampled) -> "<out>_noisy" (rgba16f: visibility
   and the view-space normal). Depth only: positions come from the depth through the inverse
   projection, normals from the neighbours' positions (no G-buffer needed, so it works for the
   forward, clustered and deferred modes alike; the deferred G-buffer's normal would be a
   little sharper on bumpy materials and is the obvious later option). No depth mip chain: the
   scenes this engine renders afford full-resolution samples (XeGTAO's mips only save
   bandwidth at large radii). The slices' rotation and the steps' jitter come from a fixed
   4 x 4 Bayer matrix, so tests/ssao_reference.py computes the same numbers.
2. denoise: a depth-aware 5 x 5 bilateral filter into "<out>" (R16_SFLOAT, 1 = unoccluded).
3. optional composite: "<hdr>" *= ao in place (COMPUTE_READ_WRITE).

Where AO belongs: physically it scales only the ambient / indirect light (the environment's
irradiance and prefiltered specular, or the flat ambient), never the direct lights, which have
their own shadows. What integrating it into the renderer needs:
- forward and clustered modes: the lit fragment shaders already multiply their ambient by the
  material's `occlusion` (mesh_fragment.glsl: `environment_ambient(..., occlusion)` and the
  flat `g.ambient` line); they would multiply it by `texelFetch(ao, ivec2(gl_FragCoord.xy))`
  (a new sampled binding in the frame's set, render/layouts.py). "ao" must exist before the
  lit pass draws, so these modes need a depth prepass of the opaque geometry (or the occlusion
  culling's early depth, where it holds all of it) and the lit pass declares "ao"
  FRAGMENT_SAMPLED;
- deferred mode: the G-buffer pass writes the ambient term into the HDR image together with the
  depth, so SSAO cannot come before it; the ambient would go to its own target (or its inputs
  into the G-buffer) and deferred_light.comp, which runs after the G-buffer, would add it
  multiplied by "ao" (declared COMPUTE_SAMPLED);
- MSAA: the passes sample a single-sample depth (texelFetch of a sampler2D): a multisampled
  depth needs a resolve first (dynamic rendering resolves depth with SAMPLE_ZERO);
- the depth image needs VK_IMAGE_USAGE_SAMPLED (the graph adds it to a transient it makes; an
  imported one must be made with it), and the renderer sets `SsaoView.projection` from the
  frame's CameraMatrices.projection each frame (the passes' keys follow it: frame replay sees
  a moved camera).
Until then `add_ssao(..., composite="hdr")` multiplies the whole lit HDR image before the tone
map: a common fallback, which also darkens direct light in creases (slightly too dark there).

Use (a plugin's one line, once the renderer's graph has "depth"):

    view = add_ssao(graph, SsaoSettings(radius=0.5), depth="depth", out="ao", composite="hdr")
    view.projection = camera.projection        # each frame before compile/execute
"""

from __future__ import annotations

from typing import Any

from ...errors import UsageError
from .ssao_passes import CompositePass, DenoisePass, GtaoPass
from .ssao_settings import MAX_SLICES, MAX_STEPS, SsaoSettings, SsaoView, push_constants

__all__ = ["MAX_SLICES", "MAX_STEPS", "SsaoSettings", "SsaoView", "add_ssao", "push_constants"]


def add_ssao(
    graph: Any,
    settings: SsaoSettings | None = None,
    depth: str = "depth",
    out: str = "ao",
    *,
    composite: str | None = None,
    view: SsaoView | None = None,
    before: str | None = None,
) -> SsaoView:
    """Add GTAO's passes to `graph` (reading the depth image `depth`, writing the R16_SFLOAT
    image `out`), and with `composite` the pass multiplying that HDR image by it; `before`:
    the pass to place them ahead of (the tone map). Returns the SsaoView to set the projection
    on. `out` is not made an output: a pass reading it (or the composite) keeps them alive."""
    settings = settings if settings is not None else SsaoSettings()
    if not isinstance(settings, SsaoSettings):
        raise UsageError(f"add_ssao takes SsaoSettings, not {settings!r}")
    view = view if view is not None else SsaoView()
    prefix = "ssao" if out == "ao" else f"ssao_{out}"
    noisy = f"{out}_noisy"
    passes = [
        GtaoPass(f"{prefix}_gtao", settings, view, graph, depth, noisy),
        DenoisePass(f"{prefix}_denoise", settings, view, graph, depth, noisy, out),
    ]
    if composite is not None:
        passes.append(CompositePass(f"{prefix}_composite", settings, view, graph, out, composite))
    for p in passes:
        graph.add_pass(p, before=before)
    return view
