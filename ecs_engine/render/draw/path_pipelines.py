"""A render path's mesh pipelines per what it draws into: the path keeps the (plain, mirrored)
pair made for each (AttachmentFormats, G-buffer or not) it was asked to draw into, so a change of
the target's form (gpu/scene_attachments.py: straight into the target, HDR colour, the G-buffer) picks
the pair made for it, or makes one, without a device wait or remaking the others: pipelines for
dynamic rendering are compatible by formats alone. All of them go with the path."""

from __future__ import annotations

from dataclasses import replace
from functools import partial
from typing import Any

from ...gpu.owned import Owned
from ...gpu.pipeline import AttachmentFormats
from .path import PathContext

Key = tuple[AttachmentFormats | None, bool]


class PipelinesPerTarget:
    """A mixin for the render paths: `ctx` is the path's context (its `formats` and `gbuffer` say
    what it draws into now), `pipelines` the pair for it; `_make_pipelines(ctx)` makes a pair."""

    ctx: PathContext
    pipelines: tuple[Any, Any]

    def _make_pipelines(self, ctx: PathContext) -> tuple[Any, Any]:
        raise NotImplementedError

    def _first_pipelines(self) -> None:
        """The pair for the context the path was made with."""
        self._pipelines_made: dict[Key, tuple[Any, Any]] = {}
        self._pipelines_owned = Owned(self.ctx.device)
        self.pipelines = self._pipelines_made[(self.ctx.formats, self.ctx.gbuffer)] = self._own(self.ctx)

    def _own(self, ctx: PathContext) -> tuple[Any, Any]:
        """A pair made for `ctx`, owned by the path's scope of pipelines."""
        pair = self._make_pipelines(ctx)
        for pipeline in pair:
            self._pipelines_owned.add(pipeline, partial(_destroy, ctx.device, pipeline))
        return pair

    def draw_into(self, formats: AttachmentFormats, gbuffer: bool) -> None:
        """Draw into attachments of `formats` (the G-buffer's with `gbuffer`) from the next
        chunk recorded: the pair made for them, made now the first time (on failure nothing
        changes)."""
        ctx = self.ctx
        if (formats is ctx.formats or formats == ctx.formats) and gbuffer == ctx.gbuffer:
            return
        key = (formats, gbuffer)
        new = replace(ctx, formats=formats, gbuffer=gbuffer)
        made = self._pipelines_made.get(key)
        if made is None:
            made = self._pipelines_made[key] = self._own(new)
        self.ctx, self.pipelines = new, made

    def _destroy_pipelines(self) -> None:
        owned = self.__dict__.pop("_pipelines_owned", None)
        if owned is not None:
            owned.destroy()
        self.__dict__.pop("_pipelines_made", None)
        self.__dict__.pop("pipelines", None)


def _destroy(device: Any, pipeline: Any) -> None:
    device.vk.vkDestroyPipeline(device.handle, pipeline, None)
