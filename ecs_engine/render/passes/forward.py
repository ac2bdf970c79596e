"""The scene's forward rendering and the hdr-stage post effects' seam as passes of the output
graph (render/passes/output_graph.py), one shape per target form (gpu/scene_attachments.py's
FORMS):

- `direct`: "target" cleared to the background and "depth" cleared to far (0.0, reverse-Z), a
  transient of the graph (nothing after the rendering reads it: never stored);
- `hdr`: "hdr" cleared and "depth" cleared; with MSAA "hdr_msaa" (n samples) cleared and
  resolved into "hdr" at the rendering's end, and "depth" of n samples;
- `deferred`: "hdr" and "depth" loaded (the G-buffer pass and the lighting wrote them, left in
  GENERAL and DEPTH_STENCIL_READ_ONLY: their imports' layout_before).

Every draw is a secondary (the chunks', the sky's, the set-aside rows', the weighted
transparency's composite and the light billboards', in that order: output_passes.py gathers
them), begun with the inheritance of the target's scene formats, so the rendering is begun with
`secondaries=True`.

`post` runs the hdr stage's post effects (OutputPasses.post, callables with their own barriers
and private graphs) on "hdr" and the single-sample "depth", both sampled (SHADER_READ_ONLY), as
the seam has always promised them. It reads both even without an effect: the tone map samples
"hdr" anyway, and a single-sample depth in SHADER_READ_ONLY is what the effects' next frame's
descriptors expect.
"""

from __future__ import annotations

from typing import Any

from ...gpu.scene_attachments import DEPTH_FORMAT_NAME
from ..graph import Access, ImageDesc, Load, Pass

FAR = (0.0, 0.0, 0.0, 0.0)  # reverse-Z's far plane: depth cleared to 0.0


class Forward(Pass):
    """The scene's rendering in one form (see the module); `frame` carries this frame's
    secondaries and background."""

    name = "forward"

    def __init__(self, frame: Any, form: str, samples: int) -> None:
        self.frame, self.form, self.samples = frame, form, samples

    def attachments(self) -> tuple[tuple[str, ...], str, tuple[str | None, ...] | None]:
        """(colours, depth, resolves) of the rendering."""
        if self.form == "direct":
            return ("target",), "depth", None
        if self.form == "hdr" and self.samples > 1:
            return ("hdr_msaa",), "depth", ("hdr",)
        return ("hdr",), "depth", None

    def setup(self, builder: Any) -> None:
        colors, depth, resolve = self.attachments()
        for name, access in self.frame.reads:  # what the scene's passes wrote for its draws
            builder.read(name, access)
        if self.form == "deferred":  # over the lit scene
            builder.write("hdr", Access.COLOR_READ_WRITE, load=Load.LOAD)
            builder.write(depth, Access.DEPTH_WRITE, load=Load.LOAD)
            return
        if self.form == "direct":
            builder.create(depth, ImageDesc(format=DEPTH_FORMAT_NAME))
        background = (*self.frame.background, 1.0)
        builder.write(colors[0], Access.COLOR_WRITE, load=Load.CLEAR, clear=background)
        if resolve is not None:
            builder.write("hdr", Access.RESOLVE_WRITE)
        builder.write(depth, Access.DEPTH_WRITE, load=Load.CLEAR, clear=FAR)

    def record(self, cb: Any, ctx: Any) -> None:
        colors, depth, resolve = self.attachments()
        ctx.begin_rendering(colors=colors, depth=depth, resolve=resolve, secondaries=True)
        secondaries = self.frame.secondaries
        if secondaries:
            ctx.vk.lib.vkCmdExecuteCommands(cb, len(secondaries), ctx.vk.ffi.new("VkCommandBuffer[]", secondaries))
        ctx.end_rendering()  # with MSAA: the resolve


class PostSeam(Pass):
    """The hdr-stage post effects (see the module), in order; nothing without one."""

    name = "post"

    def __init__(self, output: Any, samples: int) -> None:
        self.output, self.samples = output, samples

    def setup(self, builder: Any) -> None:
        builder.read("hdr", Access.COMPUTE_SAMPLED)
        if self.samples == 1:  # a multisampled depth is not stored for the effects
            builder.read("depth", Access.COMPUTE_SAMPLED)
        builder.side_effect()  # the effects write "hdr" behind the graph's back (their own barriers)

    def record(self, cb: Any, ctx: Any) -> None:
        output = self.output
        if not output.post:
            return
        inputs = output.inputs
        if inputs is None or inputs.hdr is not output.target.hdr_image:
            raise RuntimeError("OutputPasses.begin_post(camera) was not called for this frame's target")
        for post in output.post:
            post(cb, inputs)
