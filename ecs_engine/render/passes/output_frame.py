"""The output graph's frame (what its passes draw with this frame) and its two passes of its
own: the tone map into the target (or the first ldr image) and the UI over the target, or, with
a `window` (the editor's viewport: render/frame/viewport.py), the UI into the window with the
target sampled as one of its images (render/passes/output_graph.py builds the graph)."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any, NamedTuple

from ..graph import UNREPLAYABLE, Access, ImageDesc, Load, Pass
from .readback import Copy


class WindowImage(NamedTuple):
    """The window's image of a frame whose target is a texture the UI shows (the editor's
    viewport): the overlay draws it whole, the readback reads it, it is presented."""

    image: Any
    view: Any
    format: int
    extent: tuple[int, int]
    final_layout: int  # a VkImageLayout: the window target's (TRANSFER_SRC headless, PRESENT_SRC)


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
    window: WindowImage | None = None  # the window the UI draws into, the target sampled (see WindowImage)
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
    """The UI over the finished target (loaded, blended over it); nothing without an overlay.
    With a `window` the UI draws the window instead: cleared to the background, the panels and
    the target as an image among them (sampled: the graph's barrier takes it to SHADER_READ_ONLY)."""

    name = "imgui"

    def __init__(self, frame: OutputFrame) -> None:
        self.frame = frame

    def setup(self, builder: Any) -> None:
        frame = self.frame
        if frame.overlay is None:  # none: culled, with its barrier
            return
        if frame.window is not None:
            builder.read("target", Access.FRAGMENT_SAMPLED)
            builder.write("window", Access.COLOR_WRITE, load=Load.CLEAR, clear=(*frame.background, 1.0))
        else:
            builder.write("target", Access.COLOR_READ_WRITE, load=Load.LOAD)

    def declares(self) -> Hashable:
        return (self.frame.overlay is not None, self.frame.window is not None)

    def record(self, cb: Any, ctx: Any) -> None:
        overlay = self.frame.overlay
        if overlay is None:
            return
        into = "window" if self.frame.window is not None else "target"
        width, height = ctx.image(into).extent  # the whole image (a camera view's graph: not its extent)
        ctx.begin_rendering(colors=(into,))
        overlay.record(cb, self.frame.slot, width, height)
        ctx.end_rendering()

    def key(self) -> Hashable:
        """The UI draws anew each frame: a frame with an overlay is never replayed."""
        return UNREPLAYABLE if self.frame.overlay is not None else None
