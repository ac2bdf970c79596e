"""The frame graph's imports: images and buffers owned outside it, imported again each frame.
Each is made once per distinct arguments and kept (a frame slot's buffers and a swapchain's
images come back every few frames), so a frame whose imports are those of an earlier one
builds nothing; only a change of shape (compile_key) makes the graph compile again."""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

from ...errors import UsageError
from ...gpu.functions import handle_int
from .compile import Imported
from .resources import GraphBuffer, GraphImage, format_name, layout_name

TOKEN = object()  # marks a caller's token among the argument tuples
KEPT = 4  # arguments remembered per name: a swapchain's images or the frame slots; more is churn


class Imports:
    def __init__(self, vk: Any, load_vk: Callable[[], Any]) -> None:
        """`vk`: the device's binding (None for a graph that only plans); `load_vk` loads one
        when a Vulkan enum must be named without a device."""
        self.vk, self._load_vk = vk, load_vk
        self.by_name: dict[str, Imported] = {}
        # per name: what each distinct call made, with its handles as integers and the
        # GraphImage/GraphBuffer passes record with
        self._made: dict[str, dict[tuple, tuple[Imported, tuple[Any, Any], Any]]] = {}
        self.images: dict[str, GraphImage] = {}  # the current imports as passes see them
        self.buffers: dict[str, GraphBuffer] = {}
        self._ints: dict[str, tuple[Any, Any]] = {}  # the handle and view as integers
        self._names: list[str] | None = None  # sorted
        self._handles: tuple | None = None  # handles()' answer until an import changes
        self._shared = False  # the dicts are a snapshot's: copied before a change (_use)
        self._state: object | None = None  # see `state`
        self._states: dict[tuple, tuple[object, tuple]] = {}

    def image(
        self,
        name: str,
        handle: Any,
        view: Any,
        format: Any,
        extent: tuple[int, int],
        mips: int,
        samples: int,
        layout_before: Any,
        layout_after: Any,
        mip_views: tuple[Any, ...],
        layers: int,
        layer_views: tuple[Any, ...],
        stage_before: str | tuple[str, ...],
        token: Hashable = None,
    ) -> bool:
        """Import an image (see FrameGraph.import_image); True when its shape changed."""
        args: tuple = (handle, view, format, extent, mips, samples, layout_before, layout_after, mip_views, layers)
        args += (layer_views, stage_before)
        if token is not None:
            args = (TOKEN, token)
        kept = self._made.get(name, {}).get(args)
        if kept is not None:
            return self._use(name, *kept)
        strings = all(isinstance(v, str) for v in (format, layout_before, layout_after))
        vk = None if strings else self.vk if self.vk is not None else self._load_vk()
        fmt = format_name(vk, format)
        value = int(format) if not isinstance(format, str) else int(getattr(vk, f"VK_FORMAT_{fmt}", 0)) if vk else 0
        size, stages = (int(extent[0]), int(extent[1])), stage_names(stage_before)
        before, after = layout_name(vk, layout_before), layout_name(vk, layout_after)
        shape = (size, mips, samples, before, after, 0, mip_views, int(layers), layer_views, stages)
        return self._keep(name, args, Imported(name, "image", handle, view, fmt, value, *shape))

    def buffer(
        self,
        name: str,
        handle: Any,
        size: int,
        visible_after: bool,
        stage_before: str | tuple[str, ...],
        token: Hashable = None,
    ) -> bool:
        """Import a buffer (see FrameGraph.import_buffer); True when its shape changed."""
        args = (handle, size, visible_after, stage_before) if token is None else (TOKEN, token)
        kept = self._made.get(name, {}).get(args)
        if kept is not None:
            return self._use(name, *kept)
        stages = stage_names(stage_before)
        made = Imported(name, "buffer", handle, size=int(size), visible_after=bool(visible_after), stage_before=stages)
        return self._keep(name, args, made)

    def reuse(self, name: str, token: Hashable) -> bool | None:
        """Import again what was made for `token`: None when nothing was, else whether the
        shape changed."""
        kept = self._made.get(name, {}).get((TOKEN, token))
        return None if kept is None else self._use(name, *kept)

    def snapshot(self) -> tuple:
        """The imports as they stand, for `restore` (a frame slot's, brought back when it comes
        round again with the same inputs)."""
        handles = self.handles()  # (sorts the names)
        made = (dict(self.by_name), dict(self.images), dict(self.buffers), dict(self._ints))
        return (*made, handles, self.state, self._names)

    def restore(self, snapshot: tuple) -> None:
        """The imports of `snapshot`; the caller knows their shapes are today's (the graph's
        version is the one it was taken at), so nothing recompiles."""
        by_name, images, buffers, ints, handles, state, names = snapshot
        if state is self._state:  # the same made imports already (one frame slot, or still ones)
            return
        self.by_name, self.images, self.buffers, self._ints, self._handles = by_name, images, buffers, ints, handles
        self._names, self._shared, self._state = names, True, state

    @property
    def state(self) -> object:
        """One object per set of imports (the same made resources: a frame slot's come round
        again every few frames), what the graph keeps its recording structs by."""
        if self._state is None:
            made = (*self.images.values(), *self.buffers.values())
            key = tuple(map(id, made))
            kept = self._states.get(key)
            if kept is None:
                if len(self._states) >= 16:  # imports come and go (swapchain remakes, grown buffers)
                    self._states.clear()
                kept = self._states[key] = (object(), made)  # `made` held: the ids stay theirs
            self._state = kept[0]
        return self._state

    def handles(self) -> tuple:
        """(name, handle, view) of each import as integers, by name: what frame replay's key holds."""
        if self._handles is not None:
            return self._handles
        names = self._names
        if names is None:
            names = self._names = sorted(self.by_name)
        ints = self._ints
        self._handles = tuple((n, *ints[n]) for n in names)
        return self._handles

    def _keep(self, name: str, args: tuple, imported: Imported) -> bool:
        made = self._made.setdefault(name, {})
        if len(made) >= KEPT:
            made.clear()
        ints = (_int(self.vk, imported.handle), _int(self.vk, imported.view))
        made[args] = (imported, ints, _resource(imported))
        return self._use(name, *made[args])

    def _use(self, name: str, imported: Imported, ints: tuple[Any, Any], resource: Any) -> bool:
        old = self.by_name.get(name)
        if old is imported:
            return False
        if self._shared:  # a snapshot's dicts: this change is not the snapshot's
            self.by_name, self.images, self.buffers = dict(self.by_name), dict(self.images), dict(self.buffers)
            self._ints, self._shared = dict(self._ints), False
        self.by_name[name], self._ints[name], self._handles, self._state = imported, ints, None, None
        if imported.kind == "image":
            self.images[name] = resource
        else:
            self.buffers[name] = resource
        if old is None:
            self._names = None
        return old is None or old.compile_key != imported.compile_key


def _resource(i: Imported) -> GraphImage | GraphBuffer:
    if i.kind == "buffer":
        return GraphBuffer(i.name, i.handle, i.size)
    return GraphImage(
        i.name, i.handle, i.view, i.format_value, i.extent, i.mips, i.samples, i.mip_views, i.layers, i.layer_views
    )


def stage_names(stages: str | tuple[str, ...]) -> frozenset[str]:
    """Stage names without the Vulkan prefix and bit suffix ("COLOR_ATTACHMENT_OUTPUT")."""
    if isinstance(stages, str):
        stages = (stages,)
    names = set()
    for stage in stages:
        if not isinstance(stage, str) or not stage:
            raise UsageError(f"stage_before takes pipeline stage names, not {stage!r}")
        name = stage.removeprefix("VK_PIPELINE_STAGE_2_").removeprefix("VK_PIPELINE_STAGE_")
        names.add(name[: -len("_BIT")] if name.endswith("_BIT") else name)
    return frozenset(names)


def _int(vk: Any, handle: Any) -> Any:
    if handle is None or vk is None or isinstance(handle, int):
        return handle
    return handle_int(vk, handle)
