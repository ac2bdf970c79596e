"""A scope of owned GPU objects: each handle it makes (or is given, with its destroy function) is
registered, and `destroy()` destroys them all, last made first, once.

Code that makes several objects stops writing a `destroy` that names each one (and forgetting
one): it makes them through its scope and destroys the scope. A failure half-way through making
them leaves nothing behind either: the caller destroys the scope in its `except`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")


class Owned:
    """Registered objects and how to destroy each. `device` is anything with `vk` and `handle`
    (a gpu.device.Device); its `objects_version`, where it has one, is bumped on each make and
    destroy, as the engine's own resources do (a kept command buffer is stale after either)."""

    def __init__(self, device: Any) -> None:
        self.device = device
        self._items: list[tuple[Any, Callable[[], None]]] = []
        self.made = 0  # how many objects were ever registered (tests: a cached step makes none)

    def __len__(self) -> int:
        return len(self._items)

    def _bump(self) -> None:
        if hasattr(self.device, "objects_version"):
            self.device.objects_version += 1

    def add(self, obj: T, destroy: Callable[[], None] | None = None) -> T:
        """Own `obj`: destroyed with `destroy()`, or with `obj.destroy()` when none is given."""
        if destroy is None:
            destroy = obj.destroy  # type: ignore[attr-defined]
        self._items.append((obj, destroy))
        self.made += 1
        return obj

    def create(self, kind: str, info: Any) -> Any:
        """`vkCreate<kind>(device, info)`, destroyed by `vkDestroy<kind>` (kind: "Image",
        "ImageView", "Buffer", "Sampler", "Pipeline" is not one: pipelines are made in lists)."""
        vk, handle = self.device.vk, self.device.handle
        made = getattr(vk, f"vkCreate{kind}")(handle, info, None)
        destroy_fn = getattr(vk, f"vkDestroy{kind}")
        self._bump()
        return self.add(made, lambda: destroy_fn(handle, made, None))

    def allocation(self, allocation: Any) -> Any:
        """A suballocation of the device's block allocator, freed back to it."""
        return self.add(allocation, lambda: self.device.allocator.free(allocation))

    def release(self, obj: Any) -> None:
        """Destroy one owned object now (the others stay); an object not owned is an error."""
        for i, (item, destroy) in enumerate(self._items):
            if item is obj:
                del self._items[i]
                self._bump()
                destroy()
                return
        raise ValueError("release of an object this scope does not own")

    def destroy(self) -> None:
        """Destroy everything owned, last made first. Each object is destroyed once: a second
        call does nothing. When one destroy raises, the rest are still destroyed and the first
        error is raised afterwards."""
        items, self._items = self._items, []
        if items:
            self._bump()
        failure: BaseException | None = None
        for _, destroy in reversed(items):
            try:
                destroy()
            except BaseException as exc:  # the others must still go
                failure = failure or exc
        if failure is not None:
            raise failure

    def __enter__(self) -> Owned:
        return self

    def __exit__(self, kind: Any, value: Any, traceback: Any) -> None:
        """As a `with` block: everything is destroyed when the block ends (used for scopes that
        live only as long as a block, and to undo a half-made set when the block raises)."""
        self.destroy()
