"""The formats and sample count of a pass's attachments, known from the declarations alone: what
pipelines and secondaries drawn with dynamic rendering into them are made for."""

from __future__ import annotations

from typing import Any

from ...errors import UsageError
from ...gpu.pipeline import AttachmentFormats
from .compile import Imported
from .resources import BufferDesc, ImageDesc


def attachment_formats(
    vk: Any,
    colors: tuple[str, ...] | str,
    depth: str | None,
    descs: dict[str, ImageDesc | BufferDesc],
    imports: dict[str, Imported],
) -> AttachmentFormats:
    """`colors` and `depth` by name, among the transients' descriptions and the imports."""
    if isinstance(colors, str):
        colors = (colors,)
    values, samples = [], set()
    for name in (*colors, *([depth] if depth else [])):
        imp, desc = imports.get(name), descs.get(name)
        if imp is not None and imp.kind == "image":
            fmt, count = imp.format, imp.samples
        elif isinstance(desc, ImageDesc):
            fmt, count = desc.format_name, desc.samples
        else:
            raise UsageError(f"attachment {name!r} is neither an image a pass creates nor an imported one")
        values.append(int(getattr(vk, f"VK_FORMAT_{fmt}")))
        samples.add(count)
    if len(samples) > 1:
        raise UsageError(f"attachments {colors} {depth or ''} have different sample counts {sorted(samples)}")
    n = len(colors)
    return AttachmentFormats(tuple(values[:n]), values[n] if depth else 0, samples.pop() if samples else 1)
