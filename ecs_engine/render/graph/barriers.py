"""Barriers from declared accesses: the state of each (resource, mip, layer) is followed through
the passes that run, and before each pass one batch of barriers brings what it uses into the
layout and visibility its accesses need (synchronization2: one vkCmdPipelineBarrier2 per pass).

The plan is data (Barrier rows of Vulkan names), made without a device; `record_barriers`
turns a batch into Vulkan structs. Rules, per (resource, mip, layer):
- first use of a transient: from UNDEFINED, after the last accesses of any image placed in the
  same bytes before it (aliasing) and the frame before's uses of its memory;
- first use of an import: from its layout_before, after the work of its stage_before (any
  earlier work: ALL_COMMANDS, or a semaphore's wait stage); none for a buffer whose
  stage_before is NONE (a frame slot's, whose last use a fence covered), nor for a read of an
  image in its layout_before: what is there was made visible by whoever wrote it (a graph's
  final barrier does; graph.py's import_image), and a read after reads needs no barrier;
- a new layout, or a write after anything, or a read of a write not yet made visible to its
  stages: a barrier from the writes and reads since the last write; a write that discards the
  contents (CLEAR / DONT_CARE, not of a region) transitions from UNDEFINED;
- after the last pass, imported images go to their layout_after (none for one that is already in
  it and that no pass wrote), and the last writes of imported buffers marked visible_after are
  made visible to every later command.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from ...gpu.image_barrier import dependency, image_barrier
from .compile import Structure, subresources
from .resources import flags
from .transient import Packing

EMPTY: frozenset[str] = frozenset()
NONE = frozenset({"NONE"})  # an import's stage_before with nothing to wait for
WHOLE_SIZE = (1 << 64) - 1  # VK_WHOLE_SIZE (the binding has it as -1, which a VkDeviceSize refuses)


@dataclass(frozen=True)
class Barrier:
    """One barrier of the plan: mips base_mip.. and layers base_layer.. (count of each). Buffers
    have no mips and no layouts (None)."""

    resource: str
    base_mip: int | None
    mip_count: int
    old_layout: str | None
    new_layout: str | None
    src_stages: frozenset[str]
    src_access: frozenset[str]
    dst_stages: frozenset[str]
    dst_access: frozenset[str]
    base_layer: int = 0
    layer_count: int = 1

    def describe(self, layered: bool = False) -> str:
        """One line; `layered`: the image has several layers, so the range is always named."""
        mips = (
            ""
            if self.base_mip is None
            else f"[mip {self.base_mip}" + (f"..{self.base_mip + self.mip_count - 1}]" if self.mip_count > 1 else "]")
        )
        if self.base_mip is not None and (layered or self.base_layer or self.layer_count > 1):
            last = self.base_layer + self.layer_count - 1
            mips += f"[layer {self.base_layer}" + (f"..{last}]" if last > self.base_layer else "]")
        layouts = f" {self.old_layout} -> {self.new_layout}" if self.old_layout != self.new_layout else ""
        src = "|".join(sorted(self.src_stages)) or "NONE"
        dst = "|".join(sorted(self.dst_stages)) or "NONE"
        return f"{self.resource}{mips}{layouts} ({src} -> {dst})"


@dataclass
class _State:
    layout: str | None
    write_stages: frozenset[str] = EMPTY
    write_access: frozenset[str] = EMPTY
    read_stages: frozenset[str] = EMPTY  # since the last write
    synced_stages: frozenset[str] = EMPTY  # stages the last write was made visible to
    synced_access: frozenset[str] = EMPTY
    # the last write is an import's, before the graph, and visible to every reader (import_image)
    # as long as the layout is that it was written in: reads need no barrier, a write still
    # waits for the import's stage_before
    before_graph: bool = False


@dataclass
class _Need:
    """What one pass needs of one (resource, mip, layer): its accesses merged."""

    stages: frozenset[str]
    access: frozenset[str]
    layout: str | None
    writes: bool
    discards: bool


@dataclass
class BarrierPlan:
    before: dict[str, list[Barrier]] = field(default_factory=dict)  # pass name -> its batch
    after: list[Barrier] = field(default_factory=list)  # imports to their layout_after


Sub = tuple[str, int, int]  # (resource, mip, layer)


def _needs(s: Structure, pass_name: str) -> dict[Sub, _Need]:
    found: dict[Sub, _Need] = {}
    for use in s.uses[pass_name]:
        res = s.resources[use.resource]
        u = use.access.usage
        layout = u.layout if res.kind == "image" else None
        for mip, layer in subresources(use, res):
            had = found.get((res.name, mip, layer))
            need = _Need(frozenset(u.stages), frozenset(u.access), layout, use.write, not use.keeps_contents)
            if had is not None:
                need = _Need(
                    had.stages | need.stages,
                    had.access | need.access,
                    layout,
                    had.writes or need.writes,
                    had.discards and need.discards,
                )
            found[(res.name, mip, layer)] = need
    return found


def plan_barriers(s: Structure, packing: Packing) -> BarrierPlan:
    plan = BarrierPlan()
    states: dict[Sub, _State] = {}
    for position, pass_name in enumerate(s.order):
        rows: list[Barrier] = []
        for (name, mip, layer), need in _needs(s, pass_name).items():
            res = s.resources[name]
            image = res.kind == "image"
            st = states.get((name, mip, layer))
            row: Barrier | None = None
            at = (mip, layer)
            if st is None:
                if res.imported is not None and not image and res.imported.stage_before == NONE:
                    st = _State(None)  # nothing earlier to wait for (a frame slot's, fenced)
                elif res.imported is not None:
                    before = res.imported.layout_before if image else None
                    if image and need.discards and before != need.layout:
                        before = "UNDEFINED"
                    st = _State(before, res.imported.stage_before, frozenset({"MEMORY_WRITE"}))
                    if image and not need.writes and before == need.layout:
                        st.before_graph = True  # read as it was left: nothing to wait for
                    else:
                        row = _row(name, at, image, st.layout, need, st.write_stages, st.write_access)
                elif image:
                    src, access = _aliased_before(s, packing, states, name, position)
                    prior, prior_writes = _last_frame(s, packing, name)
                    st = _State("UNDEFINED")
                    row = _row(name, at, image, "UNDEFINED", need, src | prior, access | prior_writes)
                else:
                    st = _State(None)
                    if need.writes:  # the frame before may still read or write it (frames in flight)
                        prior, prior_writes = _last_frame(s, packing, name)
                        row = _row(name, at, image, None, need, prior, prior_writes)
            elif image and st.layout != need.layout:
                old = "UNDEFINED" if need.discards else st.layout
                row = _row(name, at, image, old, need, st.write_stages | st.read_stages, st.write_access)
            elif st.write_stages:
                seen = st.before_graph or (need.stages <= st.synced_stages and need.access <= st.synced_access)
                if need.writes or not seen:
                    row = _row(name, at, image, st.layout, need, st.write_stages | st.read_stages, st.write_access)
            elif need.writes and st.read_stages:  # a write after reads only: wait for the reads
                row = _row(name, at, image, st.layout, need, st.read_stages, EMPTY)
            if row is not None:
                rows.append(row)
            if need.writes:
                states[(name, mip, layer)] = _State(need.layout, need.stages, need.access)
                continue
            st.layout = need.layout
            st.read_stages |= need.stages
            if row is not None:  # the last write (or the transition) is now visible to these stages
                st.before_graph = False
                st.synced_stages |= need.stages
                st.synced_access |= need.access
            states[(name, mip, layer)] = st
        plan.before[pass_name] = merge_mips(rows)
    plan.after = merge_mips(_final(s, states))
    return plan


def _row(
    name: str,
    at: tuple[int, int],
    image: bool,
    old: str | None,
    need: _Need,
    src: frozenset[str],
    access: frozenset[str],
) -> Barrier:
    return Barrier(
        name,
        at[0] if image else None,
        1,
        old if image else None,
        need.layout if image else None,
        src,
        access,
        need.stages,
        need.access,
        at[1],
    )


def _aliased_before(
    s: Structure, packing: Packing, states: dict[Sub, _State], name: str, position: int
) -> tuple[frozenset[str], frozenset[str]]:
    """The stages and writes of images that lived earlier in bytes `name` now takes."""
    stages, access = EMPTY, EMPTY
    if name not in packing.placements:
        return stages, access
    for other, (_, last) in s.lifetimes.items():
        if other == name or last >= position or other not in packing.placements:
            continue
        if packing.overlapping(name, other):
            for (res, _, _), st in states.items():
                if res == other:
                    stages |= st.write_stages | st.read_stages
                    access |= st.write_access
    return stages, access


def _last_frame(s: Structure, packing: Packing, name: str) -> tuple[frozenset[str], frozenset[str]]:
    """The stages and writes of every use of the memory transient `name` takes (its own and those
    of images aliased with it), for its first use's barrier to wait on: the frames in flight run
    the same graph over the same transients, and a barrier's first scope reaches the commands of
    earlier submissions on the queue, so the frame before's last reads and writes of that memory
    are waited for (a write after read there needs no more than this execution dependency)."""
    users = {name}
    if name in packing.placements:
        users |= {o for o in packing.placements if o != name and packing.overlapping(name, o)}
    stages: set[str] = set()
    writes: set[str] = set()
    for pass_name in s.order:
        for use in s.uses[pass_name]:
            if use.resource in users:
                stages.update(use.access.usage.stages)
                if use.write:
                    writes |= {a for a in use.access.usage.access if "WRITE" in a}
    return frozenset(stages), frozenset(writes)


def _final(s: Structure, states: dict[Sub, _State]) -> list[Barrier]:
    rows = []
    for name, res in s.resources.items():
        imp = res.imported
        if imp is not None and res.kind == "buffer" and imp.visible_after:
            st = states.get((name, 0, 0))
            if st is not None and st.write_stages:
                everything = (frozenset({"ALL_COMMANDS"}), frozenset({"MEMORY_READ", "MEMORY_WRITE"}))
                rows.append(Barrier(name, None, 1, None, None, st.write_stages, st.write_access, *everything))
            continue
        if imp is None or res.kind != "image" or imp.layout_after == "UNDEFINED":
            continue
        present = imp.layout_after == "PRESENT_SRC_KHR"
        dst_stages = frozenset({"NONE"} if present else {"ALL_COMMANDS"})
        dst_access = frozenset({"NONE"} if present else {"MEMORY_READ", "MEMORY_WRITE"})
        for mip in range(res.mips):
            for layer in range(res.layers):
                st = states.get((name, mip, layer))
                if st is None:
                    st = _State(imp.layout_before, imp.stage_before, frozenset({"MEMORY_WRITE"}))
                    if imp.layout_before == imp.layout_after:
                        continue
                elif st.layout == imp.layout_after and (st.before_graph or not st.write_stages):
                    continue  # as it was, or as its last barrier left it: nothing written since
                src = st.write_stages | st.read_stages
                tail = (imp.layout_after, src, st.write_access, dst_stages, dst_access, layer)
                rows.append(Barrier(name, mip, 1, st.layout, *tail))
    return rows


def merge_mips(rows: list[Barrier]) -> list[Barrier]:
    """Barriers of neighbouring layers of one mip, then of neighbouring mips over the same layers,
    of one image that differ in nothing else become one."""
    return _merge(_merge(rows, layers=True), layers=False)


def _merge(rows: list[Barrier], layers: bool) -> list[Barrier]:
    merged: list[Barrier] = []
    for row in rows:
        last = merged[-1] if merged else None
        if last is None or row.base_mip is None or last.base_mip is None or last.resource != row.resource:
            merged.append(row)
            continue
        if _tail(last) != _tail(row):
            merged.append(row)
        elif layers and last.base_mip == row.base_mip and last.base_layer + last.layer_count == row.base_layer:
            merged[-1] = replace(last, layer_count=last.layer_count + row.layer_count)
        elif (
            not layers
            and (last.base_layer, last.layer_count) == (row.base_layer, row.layer_count)
            and last.base_mip + last.mip_count == row.base_mip
        ):
            merged[-1] = replace(last, mip_count=last.mip_count + row.mip_count)
        else:
            merged.append(row)
    return merged


def _tail(b: Barrier) -> tuple:
    return (b.old_layout, b.new_layout, b.src_stages, b.src_access, b.dst_stages, b.dst_access)


def dependency_info(
    vk: Any,
    rows: list[Barrier],
    images: dict[str, Any],
    buffers: dict[str, Any],
    aspects: dict[str, int],
    drop: frozenset[str] = EMPTY,
) -> Any:
    """The VkDependencyInfo of these rows (images/buffers: name -> handle), for one
    vkCmdPipelineBarrier2, without the stage and access names in `drop` (those of features the
    device lacks); it holds copies of its barriers, so it can be kept and recorded again."""
    image_rows, buffer_rows = [], []
    for b in rows:
        src_stage = flags(vk, "VK_PIPELINE_STAGE_2_", b.src_stages - drop)
        src_access = flags(vk, "VK_ACCESS_2_", b.src_access - drop)
        dst_stage = flags(vk, "VK_PIPELINE_STAGE_2_", b.dst_stages - drop)
        dst_access = flags(vk, "VK_ACCESS_2_", b.dst_access - drop)
        if b.base_mip is None:
            buffer_rows.append(
                vk.VkBufferMemoryBarrier2(
                    srcStageMask=src_stage,
                    srcAccessMask=src_access,
                    dstStageMask=dst_stage,
                    dstAccessMask=dst_access,
                    srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                    dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                    buffer=buffers[b.resource],
                    offset=0,
                    size=WHOLE_SIZE,
                )
            )
            continue
        image_rows.append(
            image_barrier(
                vk,
                images[b.resource],
                aspect=aspects[b.resource],
                base_mip=b.base_mip,
                mips=b.mip_count,
                base_layer=b.base_layer,
                layers=b.layer_count,
                old=getattr(vk, f"VK_IMAGE_LAYOUT_{b.old_layout}"),
                new=getattr(vk, f"VK_IMAGE_LAYOUT_{b.new_layout}"),
                src_stage=src_stage,
                src_access=src_access,
                dst_stage=dst_stage,
                dst_access=dst_access,
            )
        )
    return dependency(vk, image_rows, buffer_rows)
