"""A frame graph as text: the passes that run in order with what each reads and writes (and the
barriers the graph puts before it), the culled ones, and the transients with their sizes and
places in memory (`ecs-engine ... --print-graph`)."""

from __future__ import annotations

from .barriers import BarrierPlan
from .compile import Structure
from .resources import BufferDesc, ImageDesc
from .transient import Packing


def describe(s: Structure, packing: Packing, barriers: BarrierPlan) -> str:
    w, h = s.extent
    lines = [f"frame graph {w}x{h}: {len(s.order)} passes" + (f", culled: {', '.join(s.culled)}" if s.culled else "")]
    width = max((len(name) for name in s.order), default=0)
    for i, name in enumerate(s.order):
        uses = s.uses[name]
        reads = [u.describe() for u in uses if not u.write]
        writes = [u.describe() + (" store dont_care" if (name, u) in s.dont_store else "") for u in uses if u.write]
        flag = " (side effect)" if name in s.side_effects else ""
        lines.append(f"  {i} {name:<{width}}{flag}".rstrip())
        if reads:
            lines.append(f"      reads  {', '.join(reads)}")
        if writes:
            lines.append(f"      writes {', '.join(writes)}")
        for b in barriers.before[name]:
            lines.append(f"      barrier {b.describe(s.resources[b.resource].layers > 1)}")
    for b in barriers.after:
        lines.append(f"  after: barrier {b.describe(s.resources[b.resource].layers > 1)}")
    if s.lifetimes:
        lines.append(f"transients: {packing.transient_bytes:,} bytes aliased, {packing.unaliased_bytes:,} unaliased")
    for name, (first, last) in s.lifetimes.items():
        desc = s.resources[name].desc
        life = f"passes {first}..{last}"
        if isinstance(desc, BufferDesc):
            lines.append(f"  {name}: buffer {desc.size:,} bytes, {life}")
            continue
        assert isinstance(desc, ImageDesc)
        iw, ih = desc.extent(s.extent)
        place = packing.placements[name]
        extra = _counts(desc.mips, desc.samples, desc.layers)
        lines.append(
            f"  {name}: {desc.format_name} {iw}x{ih}{extra}, {place.size:,} bytes "
            f"at heap {place.heap} + {place.offset:,}, {life}"
        )
    imports = [r for r in s.resources.values() if r.imported is not None]
    for res in imports:
        imp = res.imported
        assert imp is not None
        if imp.kind == "image":
            after = "" if imp.stage_before == {"ALL_COMMANDS"} else f" after {'|'.join(sorted(imp.stage_before))}"
            lines.append(
                f"  imported {res.name}: {imp.format} {imp.extent[0]}x{imp.extent[1]}"
                f"{_counts(imp.mips, imp.samples, imp.layers)}, {imp.layout_before}{after} -> {imp.layout_after}"
            )
        else:
            lines.append(f"  imported {res.name}: buffer {imp.size:,} bytes")
    return "\n".join(lines)


def _counts(mips: int, samples: int, layers: int) -> str:
    return (
        (f", {mips} mips" if mips > 1 else "")
        + (f", {samples}x MSAA" if samples > 1 else "")
        + (f", {layers} layers" if layers > 1 else "")
    )
