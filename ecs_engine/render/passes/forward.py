"""The scene's forward rendering and the hdr-stage post effects' seam as passes of the output
graph (render/passes/output_graph.py), one shape per target form (gpu/scene_attachments.py's
Form):

- `direct`: "target" cleared to the background and "depth" cleared to far (0.0, reverse-Z), a
  transient of the graph (nothing after the rendering reads it: never stored);
- `hdr`: "hdr" cleared and "depth" cleared; with MSAA "hdr_msaa" (n samples) cleared and
  resolved into "hdr" at the rendering's end, and "depth" of n samples, both transients of the
  graph (never stored);
- `deferred`: "hdr" and "depth" loaded (the G-buffer pass and the lighting wrote them:
  render/passes/deferred_passes.py), and with weighted transparency "oit_accum" and
  "oit_reveal" sampled by its composite.

Every draw is a secondary (the chunks', the sky's, the set-aside rows', the weighted
transparency's composite and the light billboards', in that order: output_passes.py gathers
them), begun with the inheritance of the target's scene formats, so the rendering is begun with
`secondaries=True`.

A hdr-stage post effect with `add_hdr` (post/bloom_effect.py, ssao_effect.py) adds its own
passes between `forward` and the tone map; one given as a callable `post(cb, inputs)` runs in a
`PostCall` pass there, with "hdr" and the single-sample "depth" sampled (SHADER_READ_ONLY), as
the seam has always promised them, its barriers its own.
"""

from __future__ import annotations

from collections.abc import Hashable
from functools import partial
from typing import Any

from ...gpu.scene_attachments import DEPTH_FORMAT_NAME, HDR_FORMAT_NAME
from ..config import Form
from ..graph import UNREPLAYABLE, Access, ImageDesc, Load, Pass
from .deferred_passes import OIT

FAR = (0.0, 0.0, 0.0, 0.0)  # reverse-Z's far plane: depth cleared to 0.0


class Forward(Pass):
    """The scene's rendering in one form (see the module); `frame` carries this frame's
    secondaries and background."""

    name = "forward"

    def __init__(self, frame: Any, form: Form, samples: int, oit: bool = False) -> None:
        self.frame, self.form, self.samples, self.oit = frame, form, samples, oit

    def attachments(self) -> tuple[tuple[str, ...], str, tuple[str | None, ...] | None]:
        """(colours, depth, resolves) of the rendering."""
        if self.form == Form.DIRECT:
            return ("target",), "depth", None
        if self.form == Form.HDR and self.samples > 1:
            return ("hdr_msaa",), "depth", ("hdr",)
        return ("hdr",), "depth", None

    def setup(self, builder: Any) -> None:
        colors, depth, resolve = self.attachments()
        for name, access in self.frame.reads:  # what the scene's passes wrote for its draws
            builder.read(name, access)
        if self.form == Form.DEFERRED:  # over the lit scene
            builder.write("hdr", Access.COLOR_READ_WRITE, load=Load.LOAD)
            builder.write(depth, Access.DEPTH_WRITE, load=Load.LOAD)
            for name in OIT if self.oit else ():  # the weighted transparency's composite samples them
                builder.read(name, Access.FRAGMENT_SAMPLED)
            return
        if self.form == Form.DIRECT or resolve is not None:  # nothing after the rendering reads them
            builder.create(depth, ImageDesc(format=DEPTH_FORMAT_NAME, samples=self.samples))
        if resolve is not None:
            builder.create(colors[0], ImageDesc(format=HDR_FORMAT_NAME, samples=self.samples))
        background = (*self.frame.background, 1.0)
        builder.write(colors[0], Access.COLOR_WRITE, load=Load.CLEAR, clear=background)
        if resolve is not None:
            builder.write("hdr", Access.RESOLVE_WRITE)
        builder.write(depth, Access.DEPTH_WRITE, load=Load.CLEAR, clear=FAR)

    def declares(self) -> Hashable:
        return (self.frame.reads, self.frame.background)

    def record(self, cb: Any, ctx: Any) -> None:
        colors, depth, resolve = self.attachments()
        ctx.begin_rendering(colors=colors, depth=depth, resolve=resolve, secondaries=True)
        # a partial is a secondary recorded now, from the compiled graph's images (the
        # weighted transparency's composite, whose set names the graph's transients)
        secondaries = [s(ctx) if isinstance(s, partial) else s for s in self.frame.secondaries]
        if secondaries:
            ctx.vk.lib.vkCmdExecuteCommands(cb, len(secondaries), ctx.vk.ffi.new("VkCommandBuffer[]", secondaries))
        ctx.end_rendering()  # with MSAA: the resolve

    def key(self) -> Hashable:
        """Its form and samples (what it loads or clears and resolves); the secondaries it
        executes are keyed by frame replay's prelude until their passes have keys."""
        return (self.form, self.samples)


class PostCall(Pass):
    """A hdr-stage post effect given as a callable `post(cb, inputs)` (OutputPasses.post's
    entries without `add_hdr`: a test's spy, a game's own effect); see the module."""

    def __init__(self, output: Any, index: int, post: Any, samples: int) -> None:
        self.name = f"post_call_{index}"
        self.output, self.post, self.samples = output, post, samples

    def setup(self, builder: Any) -> None:
        builder.read("hdr", Access.COMPUTE_SAMPLED)
        if self.samples == 1:  # a multisampled depth is not stored for the effects
            builder.read("depth", Access.COMPUTE_SAMPLED)
        builder.side_effect()  # it may write "hdr" behind the graph's back (its own barriers)

    def declares(self) -> Hashable:
        return ()  # its setup declares the same every frame

    def record(self, cb: Any, ctx: Any) -> None:
        inputs = self.output.inputs
        if inputs is None or inputs.hdr is not self.output.target.hdr_image:
            raise RuntimeError("OutputPasses.begin_post(camera) was not called for this frame's target")
        self.post(cb, inputs)

    def key(self) -> Hashable:
        """The effect's key of this frame's inputs; an effect without one makes every frame record."""
        key = getattr(self.post, "key", None)
        return UNREPLAYABLE if key is None else key(self.output.inputs)
