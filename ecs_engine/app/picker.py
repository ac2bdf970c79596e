"""`Picker`: what is drawn under a point of the view, as a world resource (PickingPlugin).

    hit = world.resources[Picker].under_pointer(world)    # or .pick(world, x, y)
    if hit is not None:
        world.destroy(hit.entity)                          # hit.point, hit.distance too

It is render/picking.py's ray against the meshes the renderer draws, with the view's size taken
from the input (the window's size in a window, the image's headless, the Scene window's in the
editor: InputState.view), so a click's position is all a game passes.
"""

from __future__ import annotations

from typing import Any

from ..ecs.world import World
from ..render.picking import Pick, pick
from ..systems import InputState


class Picker:
    def __init__(self, registry: Any) -> None:
        self.registry = registry  # the renderer's MeshRegistry

    def pick(self, world: World, x: float, y: float, size: tuple[float, float] | None = None) -> Pick | None:
        """The entity drawn nearest under (x, y), pixels from the view's top left, or None.
        `size`: the view's width and height (default: the input's viewport)."""
        width, height = size or _viewport(world)
        if width <= 0 or height <= 0:
            return None
        return pick(world, self.registry, x, y, width, height)

    def under_pointer(self, world: World) -> Pick | None:
        """The entity under the mouse pointer, or None (also while the UI has the mouse)."""
        state = world.resources.get(InputState)
        if state is None or state.mouse_captured_by_ui:
            return None
        at, size = state.in_view()  # in the editor: the Scene window's part of the window
        return self.pick(world, at[0], at[1], size)


def _viewport(world: World) -> tuple[float, float]:
    state = world.resources.get(InputState)
    return state.viewport if state is not None else (0.0, 0.0)
