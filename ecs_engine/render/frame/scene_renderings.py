"""What a frame drawing into a target's output image needs of it (output_passes.py keeps them per
output): the secondaries' begin infos; the renderings themselves, the G-buffer's included, are
the output graph's passes (render/passes/forward.py, deferred_passes.py)."""

from __future__ import annotations

from typing import Any

from ...gpu.gbuffer import gbuffer_formats
from ..config import Form
from ..draw.path import TargetState


def scene_state(
    vk: Any, target: Any, output: Any, width: int, height: int, background: tuple[float, float, float], secondaries: Any
) -> tuple[TargetState, Any]:
    """(TargetState, the scene rendering's AttachmentFormats) for drawing into `output` (one of
    the target's images: output_image) in the target's current form at this size: the begin
    infos the secondaries inherit the formats from (the chunks' in the deferred form: the
    G-buffer's, the output graph's gbuffer pass; the others': the scene's rendering's)."""
    form, attachments = target.form, target.attachments
    formats = target.formats(vk)
    begin = secondaries.begin_info_rendering(formats)
    _, view = target.output_image(output)
    direct = form == Form.DIRECT
    named = view if direct else attachments.images[-1].view  # what the state draws into, by address
    key = (int(vk.ffi.cast("uintptr_t", named)), width, height)
    state = TargetState.make(vk, key, output, begin, background)
    if form == Form.DEFERRED:  # the chunks draw in the G-buffer pass; aside_begin stays the scene's
        state.secondary_begin = secondaries.begin_info_rendering(gbuffer_formats(vk))
    return state, formats
