"""The device-free part of compiling a frame graph: which resources exist, the order the passes
run in, which are culled, and each transient's lifetime.

Order is the order passes were added: a pass that reads a resource reads what the last pass
added before it wrote there, so every dependency points backwards and the added order is always
a valid one. A read of something no earlier pass writes (and the graph does not import) is an
error, as is a read of an unknown name. Culling keeps the passes whose writes reach an output
or a side-effect pass, transitively.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

from ...errors import UsageError
from .builder import Declared, Use
from .resources import BufferDesc, ImageDesc


@dataclass(frozen=True)
class Imported:
    """An image or buffer owned outside the graph. Its handles are not part of what compile
    depends on (a swapchain hands a different image each frame): `compile_key` leaves them out."""

    name: str
    kind: str  # "image" or "buffer"
    handle: Any
    view: Any = None
    format: str = ""  # name without the prefix
    format_value: int = 0
    extent: tuple[int, int] = (0, 0)
    mips: int = 1
    samples: int = 1
    layout_before: str = "UNDEFINED"
    layout_after: str = "UNDEFINED"
    size: int = 0
    mip_views: tuple[Any, ...] = ()
    layers: int = 1
    layer_views: tuple[Any, ...] = ()
    # the stages whose work its first barrier waits for: ALL_COMMANDS, or the wait stage of the
    # semaphore that hands it over (a swapchain image: COLOR_ATTACHMENT_OUTPUT)
    stage_before: frozenset[str] = frozenset({"ALL_COMMANDS"})
    # a buffer read after the graph by work recorded outside it: its last writes are made
    # visible to every later command by the graph's final barrier
    visible_after: bool = False

    @cached_property
    def compile_key(self) -> tuple:
        return (
            self.name,
            self.kind,
            self.format,
            self.extent,
            self.mips,
            self.samples,
            self.layout_before,
            self.layout_after,
            self.size,
            self.layers,
            self.stage_before,
            self.visible_after,
        )


@dataclass(frozen=True)
class Resource:
    """A resource as the plan sees it."""

    name: str
    kind: str  # "image" or "buffer"
    mips: int
    imported: Imported | None = None
    desc: ImageDesc | BufferDesc | None = None
    created_by: str | None = None
    layers: int = 1

    @property
    def format(self) -> str:
        if self.imported is not None:
            return self.imported.format
        return self.desc.format_name if isinstance(self.desc, ImageDesc) else ""


@dataclass
class Structure:
    extent: tuple[int, int]
    order: list[str]  # the passes that run, in order
    culled: list[str]
    uses: dict[str, tuple[Use, ...]]  # of every pass, merged per resource
    side_effects: set[str]
    resources: dict[str, Resource]
    lifetimes: dict[str, tuple[int, int]] = field(default_factory=dict)  # transient -> (first, last) index
    usage: dict[str, set[str]] = field(default_factory=dict)  # transient -> usage flag names
    outputs: tuple[str, ...] = ()
    # (pass, use) of writes nothing later in the frame reads: their attachments store DONT_CARE
    dont_store: frozenset[tuple[str, Use]] = frozenset()


def mips_of(use: Use, resource: Resource) -> range:
    return range(resource.mips) if use.mip is None else range(use.mip, use.mip + 1)


def layers_of(use: Use, resource: Resource) -> range:
    return range(resource.layers) if use.layer is None else range(use.layer, use.layer + 1)


def subresources(use: Use, resource: Resource) -> list[tuple[int, int]]:
    """The (mip, layer) pairs a use covers, mips outer (a buffer has one: (0, 0))."""
    if resource.kind != "image":
        return [(0, 0)]
    return [(m, k) for m in mips_of(use, resource) for k in layers_of(use, resource)]


def _resources(passes: list[tuple[str, Declared]], imports: dict[str, Imported]) -> dict[str, Resource]:
    found: dict[str, Resource] = {
        name: Resource(name, imp.kind, imp.mips if imp.kind == "image" else 1, imported=imp, layers=max(1, imp.layers))
        for name, imp in imports.items()
    }
    for pass_name, declared in passes:
        for name, desc in declared.creates:
            if name in found:
                was = found[name]
                by = "the graph imports it" if was.imported else f"pass {was.created_by!r} creates it too"
                raise UsageError(f"pass {pass_name!r} creates {name!r}, but {by}")
            kind = "image" if isinstance(desc, ImageDesc) else "buffer"
            mips = desc.mips if isinstance(desc, ImageDesc) else 1
            layers = desc.layers if isinstance(desc, ImageDesc) else 1
            found[name] = Resource(name, kind, mips, desc=desc, created_by=pass_name, layers=layers)
    return found


def _check_use(pass_name: str, use: Use, res: Resource | None) -> Resource:
    verb = "writes" if use.write else "reads"
    if res is None:
        raise UsageError(
            f"pass {pass_name!r} {verb} {use.resource!r}, which no pass creates and the graph does not import"
        )
    if res.kind == "image" and not use.access.for_images:
        raise UsageError(f"pass {pass_name!r} {verb} image {res.name!r} as {use.access.name}, a buffer access")
    if res.kind == "buffer" and not use.access.for_buffers:
        raise UsageError(f"pass {pass_name!r} {verb} buffer {res.name!r} as {use.access.name}, an image access")
    if use.mip is not None and (res.kind == "buffer" or use.mip >= res.mips):
        raise UsageError(f"pass {pass_name!r} {verb} mip {use.mip} of {res.name!r}, which has {res.mips} mip(s)")
    if use.layer is not None and (res.kind == "buffer" or use.layer >= res.layers):
        raise UsageError(
            f"pass {pass_name!r} {verb} layer {use.layer} of {res.name!r}, which has {res.layers} layer(s)"
        )
    return res


def _check_layouts(pass_name: str, uses: tuple[Use, ...], resources: dict[str, Resource]) -> None:
    """One pass sees each (resource, mip, layer) in one layout: two accesses needing two are an
    error."""
    seen: dict[tuple[str, int, int], Use] = {}
    for use in uses:
        if resources[use.resource].kind != "image":  # a buffer has no layout: any accesses mix
            continue
        for mip, layer in subresources(use, resources[use.resource]):
            other = seen.setdefault((use.resource, mip, layer), use)
            if other.access.usage.layout != use.access.usage.layout:
                raise UsageError(
                    f"pass {pass_name!r} uses mip {mip} of {use.resource!r} as both {other.access.name} "
                    f"and {use.access.name}, which need different layouts"
                )


def plan_structure(
    passes: list[tuple[str, Declared]],
    imports: dict[str, Imported],
    outputs: tuple[str, ...],
    extent: tuple[int, int],
) -> Structure:
    """Order, culling and lifetimes of these passes (in the order added)."""
    resources = _resources(passes, imports)
    index = {name: i for i, (name, _) in enumerate(passes)}
    last_writer: dict[tuple[str, int, int], int] = {}
    writers: dict[str, list[str]] = {}
    for pass_name, declared in passes:
        for use in declared.uses:
            if use.write:
                writers.setdefault(use.resource, []).append(pass_name)
    deps: list[set[int]] = []
    for i, (pass_name, declared) in enumerate(passes):
        needs: set[int] = set()
        for use in declared.uses:
            res = _check_use(pass_name, use, resources.get(use.resource))
            if not use.keeps_contents:
                continue
            for mip, layer in subresources(use, res):
                writer = last_writer.get((res.name, mip, layer))
                if writer is not None:
                    needs.add(writer)
                elif res.imported is None and use.needs_writer:
                    later = [w for w in writers.get(res.name, []) if index[w] >= i]
                    after = f" (written only by {', '.join(later)}, added after it)" if later else ""
                    what = "reads" if not use.write else "loads"
                    where = "" if res.mips == 1 else f"mip {mip} of "
                    where += "" if res.layers == 1 else f"layer {layer} of "
                    raise UsageError(
                        f"pass {pass_name!r} {what} {where}{res.name!r}, which no pass before it writes "
                        f"and the graph does not import{after}"
                    )
        _check_layouts(pass_name, declared.uses, resources)
        for use in declared.uses:
            if use.write:
                for mip, layer in subresources(use, resources[use.resource]):
                    last_writer[(use.resource, mip, layer)] = i
        deps.append(needs)

    roots = {i for i, (_, d) in enumerate(passes) if d.side_effect}
    for name in outputs:
        out = resources.get(name)
        if out is None:
            raise UsageError(f"output {name!r} is neither created by a pass nor imported")
        subs = [(name, m, k) for m in range(out.mips) for k in range(out.layers)]
        found = [last_writer[sub] for sub in subs if sub in last_writer]
        if not found and out.imported is None:
            raise UsageError(f"output {name!r} is written by no pass")
        roots.update(found)
    kept: set[int] = set()
    todo = list(roots)
    while todo:
        i = todo.pop()
        if i not in kept:
            kept.add(i)
            todo.extend(deps[i] - kept)

    order = [name for i, (name, _) in enumerate(passes) if i in kept]
    structure = Structure(
        extent=extent,
        order=order,
        culled=[name for i, (name, _) in enumerate(passes) if i not in kept],
        uses={name: d.uses for name, d in passes},
        side_effects={name for name, d in passes if d.side_effect},
        resources=resources,
        outputs=tuple(outputs),
    )
    _lifetimes(structure)
    structure.dont_store = _dont_store(structure)
    return structure


def _lifetimes(s: Structure) -> None:
    """First and last position among the passes that run of each transient they use, and the
    usage flags those uses need. An output lives to the end of the frame."""
    for position, pass_name in enumerate(s.order):
        for use in s.uses[pass_name]:
            res = s.resources[use.resource]
            if res.imported is not None:
                continue
            first, _ = s.lifetimes.get(res.name, (position, position))
            s.lifetimes[res.name] = (first, position)
            usage = use.access.usage
            s.usage.setdefault(res.name, set()).update(usage.image_usage if res.kind == "image" else usage.buffer_usage)
    for name in s.outputs:
        if name in s.lifetimes:
            s.lifetimes[name] = (s.lifetimes[name][0], max(len(s.order) - 1, 0))


def _dont_store(s: Structure) -> frozenset[tuple[str, Use]]:
    """Writes of transient images (not outputs) that no later pass of the frame sees: before
    anything reads or keeps them, a later write discards them, or nothing uses them again (an
    MSAA image after its resolve, a depth nobody samples). Storing them would be wasted bandwidth."""
    found = set()
    for i, pass_name in enumerate(s.order):
        for use in s.uses[pass_name]:
            res = s.resources[use.resource]
            if use.write and res.kind == "image" and res.imported is None and res.name not in s.outputs:
                if not _seen_later(s, i, res, set(subresources(use, res))):
                    found.add((pass_name, use))
    return frozenset(found)


def _seen_later(s: Structure, position: int, res: Resource, pending: set[tuple[int, int]]) -> bool:
    for later in s.order[position + 1 :]:
        uses = [u for u in s.uses[later] if u.resource == res.name]
        if any(u.keeps_contents and pending & set(subresources(u, res)) for u in uses):
            return True
        for u in uses:
            pending -= set(subresources(u, res))
        if not pending:
            return False
    return False
