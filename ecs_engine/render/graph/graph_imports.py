"""The frame graph's import calls (FrameGraph's, apart for its size): images and buffers owned
outside the graph, imported again each frame, and their snapshot for frame replay. The table
behind them is imports.py's `Imports`; a change of an import's shape moves the graph's version,
so the next compile plans again."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from ...errors import UsageError
from .imports import Imports


class GraphImports:
    """FrameGraph's import methods; the attributes they use are the graph's."""

    _table: Imports
    _version: int

    def _changed(self) -> None:
        raise NotImplementedError

    def import_image(
        self,
        name: str,
        *,
        handle: Any,
        view: Any,
        format: Any,
        extent: tuple[int, int],
        mips: int = 1,
        samples: int = 1,
        layout_before: Any,
        layout_after: Any,
        mip_views: tuple[Any, ...] = (),
        layers: int = 1,
        layer_views: tuple[Any, ...] = (),
        stage_before: str | tuple[str, ...] = "ALL_COMMANDS",
        token: Hashable = None,
    ) -> None:
        """An image owned outside the graph; importing a name again replaces it (a new
        swapchain image each frame: only a change of format, size, layers, layouts or
        stage_before recompiles). `layers`: an array image, `layer_views` one view of each
        layer (what `begin_rendering(layer=k)` renders to). `stage_before`: the pipeline stages
        (names as "COLOR_ATTACHMENT_OUTPUT") whose earlier work its first barrier waits for; a
        swapchain image names the acquire semaphore's wait stage so that the two chain. Its
        contents in layout_before are taken as visible to readers (a graph's final barrier makes
        them so; work outside a graph makes its own): a first read in that layout waits for
        nothing. `token`: see reuse_import."""
        if layers < 1 or (layer_views and len(layer_views) != layers):
            raise UsageError(f"image {name!r}: {layers} layer(s) and {len(layer_views)} layer view(s)")
        views = (tuple(mip_views), layers, tuple(layer_views))
        shape = ((int(extent[0]), int(extent[1])), mips, samples, layout_before, layout_after, *views)
        if self._table.image(name, handle, view, format, *shape, stage_before, token):
            self._changed()

    def import_buffer(
        self,
        name: str,
        *,
        handle: Any,
        size: int,
        visible_after: bool = False,
        stage_before: str | tuple[str, ...] = "ALL_COMMANDS",
        token: Hashable = None,
    ) -> None:
        """A buffer owned outside the graph (a frame slot's: import it again each frame).
        `visible_after`: commands recorded after the graph read it, so its last writes get a
        final barrier to all later commands (as images get theirs to layout_after).
        `stage_before`: as import_image's; "NONE" when nothing on the queue may still use it (a
        frame slot's buffer, whose last frame's fence was waited for): no first barrier, so
        this frame's first use need not wait for the frames still in flight."""
        if self._table.buffer(name, handle, size, visible_after, stage_before, token):
            self._changed()

    def import_slot_buffers(self, buffers: dict[str, Any]) -> None:
        """A frame slot's buffers (objects with .handle and .size) whose last use was fenced:
        nothing to wait for. Each is made into an import once (its token: the buffer's identity,
        handle and size: all an import of it is made from)."""
        for name, buffer in buffers.items():
            token = (id(buffer), buffer.handle, buffer.size)
            if not self.reuse_import(name, token):
                self.import_buffer(name, handle=buffer.handle, size=buffer.size, stage_before="NONE", token=token)

    def reuse_import(self, name: str, token: Hashable) -> bool:
        """Import `name` again as an import_image/import_buffer call given `token` made it: a
        caller's cheap stand-in for the arguments, equal only where they are (an object and its
        handle); False when nothing was made for the token (import it, with the token)."""
        changed = self._table.reuse(name, token)
        if changed:
            self._changed()
        return changed is not None

    def imports_snapshot(self) -> tuple:
        """The imports as they stand (restore_imports brings them back)."""
        return (self._version, self._table.snapshot())

    def restore_imports(self, snapshot: tuple) -> bool:
        """The imports of `snapshot` again, if it was taken at this version (their shapes are
        then today's: nothing recompiles); False, and nothing done, otherwise."""
        version, imports = snapshot
        if version != self._version:
            return False
        self._table.restore(imports)
        return True
