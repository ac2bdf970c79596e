"""The editor's Hierarchy window: the Parent tree of the world, by name, selectable; drag an
entity (from the tree or the entity browser) onto another to parent it there, keeping it where
it is in the world, or onto "(no parent)" to make it a root. Only entities in a hierarchy are
listed (a million plain entities stay in the browser); the tree is rebuilt when the world's
structure or a Parent column changes.
"""

from __future__ import annotations

from typing import Any

from ..components import Name, Parent
from ..components.hierarchy import parents, set_parent
from ..ecs.errors import EcsError
from ..ecs.world import World
from .editor_layout import wrapped_colored

PAYLOAD = "ECS_ENTITY"  # an entity id dragged between the tree and the browser


def entity_label(world: World, entity: int) -> str:
    name = str(world.get(entity, Name).value) if world.has(entity, Name) else ""
    return f"{name or entity & 0xFFFFFFFF} ({entity & 0xFFFFFFFF}, gen {entity >> 32})##{entity}"


def drag_source(imgui: Any, entity: int, label: str) -> None:
    """Make the last item a drag source of `entity`."""
    if imgui.begin_drag_drop_source():
        imgui.set_drag_drop_payload_py_id(PAYLOAD, int(entity))
        imgui.text(label.split("##")[0])
        imgui.end_drag_drop_source()


def dropped(imgui: Any) -> int | None:
    """The entity dropped on the last item this frame, if any."""
    if not imgui.begin_drag_drop_target():
        return None
    payload = imgui.accept_drag_drop_payload_py_id(PAYLOAD)
    imgui.end_drag_drop_target()
    return None if payload is None else int(payload.data_id)


class HierarchyPanel:
    def __init__(self) -> None:
        self.key: Any = None
        self.roots: list[int] = []
        self.below: dict[int, list[int]] = {}
        self.rects: dict[str, tuple[float, float, float, float]] = {}
        self.status = ""

    def tree(self, world: World) -> tuple[list[int], dict[int, list[int]]]:
        """Roots (entities with children and no live parent) and each entity's children."""
        key = (
            world.structure_version,
            tuple(t.column_ticks.get((Parent, "entity"), 0) for t in world.tables),
        )
        if key != self.key:
            kids, of = parents(world)
            live = (of != -1) & world.alive(of)
            below: dict[int, list[int]] = {}
            for child, parent in zip(kids[live].tolist(), of[live].tolist()):
                below.setdefault(parent, []).append(child)
            placed = set(kids[live].tolist())
            self.roots = sorted(e for e in below if e not in placed)
            self.roots += sorted(e for e in kids[~live].tolist())  # a Parent of -1 or a dead one: a root
            self.below, self.key = below, key
        return self.roots, self.below

    def reparent(self, world: World, child: int, parent: int | None) -> None:
        try:
            set_parent(world, child, parent, keep_world=True)
            self.status = ""
        except (EcsError, ValueError) as exc:
            self.status = str(exc)

    def draw(self, imgui: Any, world: World, editor: Any) -> None:
        roots, below = self.tree(world)
        imgui.selectable("(no parent)", False)
        self._remember(imgui, "(no parent)")
        target = dropped(imgui)
        if target is not None and world.is_alive(target):
            self.reparent(world, target, None)
        if not roots:
            imgui.push_text_wrap_pos(0.0)
            imgui.text_disabled("no entity has a parent: drag one onto another")
            imgui.pop_text_wrap_pos()
        for entity in roots:
            self._node(imgui, world, editor, entity, below, 0)
        if self.status:
            wrapped_colored(imgui, (1.0, 0.4, 0.3, 1.0), self.status)

    def _node(
        self, imgui: Any, world: World, editor: Any, entity: int, below: dict[int, list[int]], depth: int
    ) -> None:
        if not world.is_alive(entity) or depth > 64:
            return
        label = entity_label(world, entity)
        flags = imgui.TreeNodeFlags_.open_on_arrow.value | imgui.TreeNodeFlags_.default_open.value
        if entity not in below:
            flags |= imgui.TreeNodeFlags_.leaf.value
        if editor.selected == entity:
            flags |= imgui.TreeNodeFlags_.selected.value
        opened = imgui.tree_node_ex(label, flags)
        self._remember(imgui, str(entity))
        if imgui.is_item_clicked() and not imgui.is_item_toggled_open():
            editor.selected = entity
        drag_source(imgui, entity, label)
        child = dropped(imgui)
        if child is not None and child != entity and world.is_alive(child):
            self.reparent(world, child, entity)
        if opened:
            for kid in below.get(entity, []):
                self._node(imgui, world, editor, kid, below, depth + 1)
            imgui.tree_pop()

    def _remember(self, imgui: Any, name: str) -> None:
        lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
        self.rects[name] = (lo.x, lo.y, hi.x, hi.y)
