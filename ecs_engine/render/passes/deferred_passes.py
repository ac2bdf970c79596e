"""The deferred form's passes before the scene's rendering, in the output graph
(render/passes/output_graph.py), in order:

    gbuffer            the opaque chunks' secondaries into "hdr" (ambient, emissive: cleared to
                       the background), "normal_roughness", "base_metallic", "material" (cleared
                       to zero, zero, NO_MATERIAL) and "depth" (cleared to far); gpu/gbuffer.py
    ray_shadows        the traced shadows' rays (render/raytracing/shadows.py) from "depth" and
                       "normal_roughness" into the lighting's shadow mask; nothing without a
                       traced light; only where the renderer traces shadows
    ray_denoise        the mask filtered (raytracing/denoise.py), reading them in compute
    deferred_lighting  the lights added into "hdr" in compute (render/lighting/deferred.py),
                       reading the G-buffer (storage images) and "depth" (sampled)
    oit_accumulate     weighted transparency's blended rows into "oit_accum" / "oit_reveal"
                       (cleared to 0 and 1) against "depth" (read-only); only with it on
                       (render/passes/oit.py; the composite in `forward` samples them)

The G-buffer's colours and weighted transparency's targets are the graph's transients (their
lifetimes do not overlap: the graph may alias them); "hdr" and "depth" are still the target's
SceneAttachments. The graph places every barrier between them (in the layouts the passes'
descriptors name: depth DEPTH_STENCIL_READ_ONLY, the rest GENERAL). The shadow mask stays the
lighting's own image (GENERAL, its barriers the ray pass's own).
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ...gpu.gbuffer import GBUFFER_FORMAT_NAMES
from ..graph import Access, ImageDesc, Load, Pass
from ..layouts import NO_MATERIAL
from .oit import ACCUMULATION_FORMAT, REVEALAGE_FORMAT

#: the G-buffer's colours after "hdr", in the mesh pipelines' attachment order (gpu/gbuffer.py)
GBUFFER = ("normal_roughness", "base_metallic", "material")
OIT = ("oit_accum", "oit_reveal")
FAR = (0.0, 0.0, 0.0, 0.0)  # reverse-Z's far plane


class GBufferViews:
    """What the lighting's and the rays' descriptor sets name (render/lighting/deferred.py,
    raytracing/shadows.py, denoise.py), in the target's SceneAttachments' shape: its depth and
    HDR colour (`images`, `depth_view`) and the graph's G-buffer transients (`gbuffer.views`).
    One per compile of a graph and attachments (OutputGraph keeps it), so those passes' "named
    is not this" checks name their sets again exactly when a compile made new transients."""

    class _Views:
        def __init__(self, views: list[Any]) -> None:
            self.views = views

    def __init__(self, attachments: Any, images: dict[str, Any]) -> None:
        self.images = attachments.images
        self.depth_view = attachments.depth_view
        self.gbuffer = self._Views([images[name].view for name in GBUFFER])


def _execute(ctx: Any, cb: Any, secondaries: Any) -> None:
    if secondaries:
        ctx.vk.lib.vkCmdExecuteCommands(cb, len(secondaries), ctx.vk.ffi.new("VkCommandBuffer[]", list(secondaries)))


class GBufferPass(Pass):
    """The G-buffer rendering of `frame.chunks` (see the module)."""

    name = "gbuffer"

    def __init__(self, frame: Any) -> None:
        self.frame = frame

    def setup(self, builder: Any) -> None:
        for name, fmt in zip(GBUFFER, GBUFFER_FORMAT_NAMES, strict=True):
            builder.create(name, ImageDesc(format=fmt))
        builder.write("hdr", Access.COLOR_WRITE, load=Load.CLEAR, clear=(*self.frame.background, 1.0))
        clears = ((0.0,) * 4, (0.0,) * 4, (float(NO_MATERIAL), 0.0, 0.0, 0.0))
        for name, clear in zip(GBUFFER, clears, strict=True):
            builder.write(name, Access.COLOR_WRITE, load=Load.CLEAR, clear=clear)
        builder.write("depth", Access.DEPTH_WRITE, load=Load.CLEAR, clear=FAR)
        for name, access in self.frame.reads:  # the GPU-culled draws (frame/scene_passes.py)
            if name.startswith("draws."):
                builder.read(name, access)

    def declares(self) -> Hashable:
        return (self.frame.reads, self.frame.background)

    def record(self, cb: Any, ctx: Any) -> None:
        ctx.begin_rendering(colors=("hdr", *GBUFFER), depth="depth", secondaries=True)
        _execute(ctx, cb, self.frame.chunks)
        ctx.end_rendering()


class RayShadowsPass(Pass):
    """The rays into the lighting's mask (see the module); `frame.ray`: the RayShadows on a
    frame with a traced light, else None."""

    name = "ray_shadows"

    def __init__(self, frame: Any, lighting: Any) -> None:
        self.frame, self.lighting = frame, lighting

    def setup(self, builder: Any) -> None:
        builder.read("depth", Access.DEPTH_SAMPLED)
        builder.read("normal_roughness", Access.RAY_READ)
        builder.side_effect()  # writes the mask, outside the graph

    def declares(self) -> Hashable:
        return ()  # its setup declares the same every frame

    def record(self, cb: Any, ctx: Any) -> None:
        shadows, frame = self.frame.ray, self.frame
        if shadows is None:
            return
        mask = self.lighting.named(frame.attachments)  # its set names this compile's G-buffer
        width, height = ctx.extent
        shadows.record_trace(cb, frame.slot, frame.frame_set, frame.attachments, mask, width, height)


class RayDenoisePass(Pass):
    """The traced mask filtered into the lighting's (where a light is soft and denoise is on)."""

    name = "ray_denoise"

    def __init__(self, frame: Any, lighting: Any) -> None:
        self.frame, self.lighting = frame, lighting

    def setup(self, builder: Any) -> None:
        builder.read("depth", Access.DEPTH_SAMPLED)
        builder.read("normal_roughness", Access.COMPUTE_READ)
        builder.side_effect()

    def declares(self) -> Hashable:
        return ()  # its setup declares the same every frame

    def record(self, cb: Any, ctx: Any) -> None:
        shadows, frame = self.frame.ray, self.frame
        if shadows is None:
            return
        mask = self.lighting.named(frame.attachments)
        width, height = ctx.extent
        shadows.record_denoise(cb, frame.slot, frame.attachments, mask, width, height)


class DeferredLightingPass(Pass):
    """render/lighting/deferred.py's dispatch (see the module)."""

    name = "deferred_lighting"

    def __init__(self, frame: Any, lighting: Any) -> None:
        self.frame, self.lighting = frame, lighting

    def setup(self, builder: Any) -> None:
        builder.read("depth", Access.DEPTH_SAMPLED)
        for name, _ in self.frame.reads:  # the light clusters and shadow maps it lights with
            if name == "clusters":
                builder.read(name, Access.COMPUTE_READ)
            elif name == "shadow_maps":
                builder.read(name, Access.DEPTH_SAMPLED)
        for name in GBUFFER:
            builder.read(name, Access.COMPUTE_READ)
        builder.write("hdr", Access.COMPUTE_READ_WRITE)

    def declares(self) -> Hashable:
        return self.frame.reads

    def record(self, cb: Any, ctx: Any) -> None:
        frame = self.frame
        width, height = ctx.extent
        self.lighting.record(cb, frame.frame_set, frame.attachments, frame.features, width, height)

    def key(self) -> Hashable:
        return self.frame.features


class OitAccumulatePass(Pass):
    """Weighted transparency's accumulation of `frame.transparent` (see the module); nothing on
    a frame without blended rows (the composite is then not drawn either)."""

    name = "oit_accumulate"

    def __init__(self, frame: Any) -> None:
        self.frame = frame

    def setup(self, builder: Any) -> None:
        for name, fmt in zip(OIT, (ACCUMULATION_FORMAT, REVEALAGE_FORMAT), strict=True):
            builder.create(name, ImageDesc(format=fmt))
        builder.write(OIT[0], Access.COLOR_WRITE, load=Load.CLEAR, clear=(0.0,) * 4)
        builder.write(OIT[1], Access.COLOR_WRITE, load=Load.CLEAR, clear=(1.0,) * 4)
        builder.read("depth", Access.DEPTH_READ)
        for name, access in self.frame.reads:  # the blended rows are lit forward: clusters, maps
            if not name.startswith("draws."):
                builder.read(name, access)

    def declares(self) -> Hashable:
        return self.frame.reads

    def record(self, cb: Any, ctx: Any) -> None:
        transparent = self.frame.transparent
        if transparent is None:
            return
        ctx.begin_rendering(colors=OIT, depth="depth", secondaries=True)
        _execute(ctx, cb, [transparent])
        ctx.end_rendering()

    def key(self) -> Hashable:
        return self.frame.transparent is not None
