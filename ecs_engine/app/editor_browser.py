"""The editor's entity browser (a part of Editor, app/editor.py, apart for its size): the ids
matching a search and a component filter, as a NumPy array rebuilt only when the world's
structure or the filter changes, and ImGui's list clipper drawing only the visible rows."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..components.name import Name
from ..ecs.world import World
from .editor_layout import push_label_room
from .editor_tree import drag_source

BROWSER_LABELS = ("id or name", "with")


@dataclass
class Browser:
    search: str = ""
    component: int = 0  # index into the component names; 0 = any
    ids: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    key: Any = None  # (structure version, search, component) the ids were built for


class BrowserPanel:
    """Editor's browser methods; the attributes they use are the editor's."""

    imgui: Any
    browser: Browser
    selected: int | None

    def _remember(self, name: str) -> None:
        raise NotImplementedError  # the editor's

    def component_names(self, world: World) -> list[str]:
        names = sorted({t.__name__ for table in world.tables for t in table.type_set})
        return ["(any component)"] + names

    def filtered_ids(self, world: World) -> np.ndarray:
        """Entity ids matching the search text (a number: that id or its index; other text: the
        names that contain it, any case) and the component filter; cached until rows come or go,
        a Name is written or the filter changes."""
        b = self.browser
        names = self.component_names(world)
        b.component = min(b.component, len(names) - 1)
        # a table's version changes whenever rows come or go
        key = (
            tuple((t.id, t.version, t.column_ticks.get((Name, "value"), 0)) for t in world.tables),
            b.search,
            names[b.component],
        )
        if b.key == key:
            return b.ids
        if b.component == 0:
            ids = world.entities()
        else:
            wanted = names[b.component]
            parts = [
                table.entities[: table.count]
                for table in world.tables
                if table.count and any(t.__name__ == wanted for t in table.type_set)
            ]
            ids = np.concatenate(parts) if parts else np.empty(0, np.int64)
        text = b.search.strip()
        if text:
            try:
                number = int(text, 0)
            except ValueError:
                named = [
                    batch.entities[np.char.find(np.char.lower(batch[Name].value), text.lower()) >= 0]
                    for batch in world.query(Name, write=())
                ]
                ids = ids[np.isin(ids, np.concatenate(named))] if named else ids[:0]
            else:
                ids = ids[(ids == number) | ((ids & 0xFFFFFFFF) == number)]
        b.ids, b.key = np.asarray(ids, dtype=np.int64), key
        return b.ids

    def _browser(self, world: World) -> None:
        imgui = self.imgui
        b = self.browser
        push_label_room(imgui, BROWSER_LABELS)
        _, b.search = imgui.input_text("id or name", b.search)
        names = self.component_names(world)
        _, b.component = imgui.combo("with", min(b.component, len(names) - 1), names)
        imgui.pop_item_width()
        ids = self.filtered_ids(world)
        imgui.text(f"{len(ids):,} entities")
        if imgui.begin_child("ids"):
            clipper = imgui.ListClipper()
            clipper.begin(len(ids))
            first = True
            while clipper.step():  # the first step measures one row, later ones the visible rows
                for row in range(clipper.display_start, clipper.display_end):
                    eid = int(ids[row])
                    name = str(world.get(eid, Name).value) if world.has(eid, Name) else ""
                    label = f"{name or eid & 0xFFFFFFFF} ({eid & 0xFFFFFFFF}, gen {eid >> 32})##{eid}"
                    if imgui.selectable(label, eid == self.selected)[0]:
                        self.selected = eid
                    drag_source(imgui, eid, label)  # onto a node of the Hierarchy window: parent it
                    if first:
                        self._remember("first row")
                        first = False
            clipper.end()
        imgui.end_child()
