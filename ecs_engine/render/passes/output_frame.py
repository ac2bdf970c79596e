"""The output graph's frame (what its passes draw with this frame) and its two passes of its
own: the tone map into the target (or the first ldr image) and the UI over the target
(render/passes/output_graph.py builds the graph)."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ..graph import UNREPLAYABLE, Access, ImageDesc, Load, Pass
from .readback import Copy


class OutputFrame:
    """What this frame's passes draw with (set before each execute)."""

    state: Any = None
    tone_map: tuple[str, float] = ("clamp", 0.0)
    overlay: Any = None
    slot: int = 0
    secondaries: tuple[Any, ...] | list[Any] = ()  # the scene rendering's, in order (output_passes.py)
    reads: tuple[Any, ...] | list[Any] = ()  # (name, Access) forward reads of the scene's passes
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)  # fixed per renderer
    readback: Copy | None = None  # the target's record_copy on a frame read back
    # the deferred form's (render/passes/deferred_passes.py; output_passes.py sets them)
    chunks: tuple[Any, ...] | list[Any] = ()  # the opaque chunks' secondaries, in the G-buffer
    frame_set: Any = None  # the slot's frame descriptor set
    features: int = 0  # the mesh pipelines' MATERIAL_FEATURES (the lighting's)
    attachments: Any = None  # GBufferViews: what the lighting's and rays' sets name (set by record)
    ray: Any = None  # the RayShadows on a frame with a traced light
    transparent: Any = None  # weighted transparency's blended rows' secondary


class ToneMapInto(Pass):
    """The output's tone map (tone_map.py's pass, owned by the output passes) into `image`
    (made by the graph when `desc` is given, else an import: the target)."""

    name = "tone_map"

    def __init__(self, output: Any, frame: OutputFrame, image: str, desc: ImageDesc | None) -> None:
        self.output, self.frame, self.image, self.desc = output, frame, image, desc

    def setup(self, builder: Any) -> None:
        if self.desc is not None:
            builder.create(self.image, self.desc)
        builder.read("hdr", Access.FRAGMENT_SAMPLED)
        builder.write(self.image, Access.COLOR_WRITE)  # every pixel: not loaded

    def declares(self) -> Hashable:
        return ()  # its setup declares the same every frame

    def record(self, cb: Any, ctx: Any) -> None:
        ctx.begin_rendering(colors=(self.image,))
        self.output.tone_map_pass.record(cb, self.frame.state, self.output.target, *self.frame.tone_map)
        ctx.end_rendering()

    def key(self) -> Hashable:
        return self.frame.tone_map


class OverlayOver(Pass):
    """The UI over the finished target (loaded, blended over it); nothing without an overlay."""

    name = "imgui"

    def __init__(self, frame: OutputFrame) -> None:
        self.frame = frame

    def setup(self, builder: Any) -> None:
        if self.frame.overlay is not None:  # none: culled, with its barrier
            builder.write("target", Access.COLOR_READ_WRITE, load=Load.LOAD)

    def declares(self) -> Hashable:
        return self.frame.overlay is not None

    def record(self, cb: Any, ctx: Any) -> None:
        overlay = self.frame.overlay
        if overlay is None:
            return
        width, height = ctx.extent
        ctx.begin_rendering(colors=("target",))
        overlay.record(cb, self.frame.slot, width, height)
        ctx.end_rendering()

    def key(self) -> Hashable:
        """The UI draws anew each frame: a frame with an overlay is never replayed."""
        return UNREPLAYABLE if self.frame.overlay is not None else None
