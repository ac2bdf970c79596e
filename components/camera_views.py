"""Several cameras: where each draws (a rectangle of the window, or an image of its own that
materials can sample), in which order, and which entities it sees.

- `Viewport` on a camera: the rectangle of its target it draws into, as fractions of the
  target's size from the top left, and its `order` among the cameras drawing into that target
  (lower first; later ones draw over). Two cameras with half-window viewports make split screen;
  a small viewport with a higher order is a picture-in-picture (a rear-view mirror, a minimap).
- `RenderTexture` on a camera: it draws into an image of `width` x `height` pixels instead of
  the window, which materials sample by the texture's `name` (a security monitor). Such images
  are drawn before the window's cameras, which may show them.
- `RenderLayers` on a camera: the layers (bits of `mask`) it draws; on a mesh entity: the layers
  it is in. Without the component both are layer 0 (mask 1), so a camera sees an entity when
  their masks share a bit. An entity its camera does not see casts no shadow in its picture
  either (the rows are left out of the frame by the extract stage, render/extract/chunks.py).

`camera_views(world)` lists the cameras that draw this frame, in drawing order. The window's
cameras are those with a Viewport and no RenderTexture, plus the one camera without either
(`active_camera`'s rule among those: the only one, or the one tagged ActiveCamera); a scene of
one camera and none of these components draws as before, that camera over the whole window.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

from ecs_engine.ecs.world import World
from ecs_engine.errors import UsageError

from .camera import ActiveCamera, Camera, RenderLayers, RenderTexture, Viewport
from .transform import Transform

DEFAULT_LAYERS = 1  # a camera or an entity without RenderLayers: layer 0


@dataclass(frozen=True)
class CameraView:
    """One camera drawing this frame. `rect` (x, y, width, height): fractions of its target;
    `texture`: (name, width, height) of its RenderTexture, or None for the window."""

    entity: int
    order: int
    rect: tuple[float, float, float, float]
    layers: int
    texture: tuple[str, int, int] | None

    def pixels(self, width: int, height: int) -> tuple[int, int, int, int]:
        """The rectangle in pixels of a target of `width` x `height` (the texture's own size for
        a texture view), edges rounded so that views sharing an edge share its pixel column and
        no pixel is left between them; at least one pixel a side."""
        if self.texture is not None:
            width, height = self.texture[1], self.texture[2]
        x, y, w, h = self.rect
        x0, y0 = round(x * width), round(y * height)
        x1, y1 = round((x + w) * width), round((y + h) * height)
        x0, y0 = min(x0, width - 1), min(y0, height - 1)
        return x0, y0, max(1, min(x1, width) - x0), max(1, min(y1, height) - y0)


def camera_views(world: World) -> tuple[CameraView, ...]:
    """The cameras that draw this frame: the render textures' first, then the window's; each
    group by order, the camera without a Viewport first among its order, then by entity id.
    Raises UsageError when no camera draws into the window, when several cameras without a
    Viewport or RenderTexture leave it ambiguous which one draws the window (as active_camera),
    or when two render textures share a name."""
    stamp = _stamp(world)
    cached = _VIEWS.get(world)
    if cached is not None and cached[0] == stamp:
        return cached[1]
    views = _camera_views(world)
    _VIEWS[world] = (stamp, views)
    return views


def _stamp(world: World) -> tuple[int, ...]:
    """A value that stays equal while no camera's Viewport, RenderTexture or RenderLayers can
    have changed (nor which entities are cameras): the tables' versions and those columns' last
    write ticks (a still scene's views cost this loop, not a rebuild)."""
    parts = [world.structure_version]
    for table in world.tables:
        if table.has(Camera):
            parts += (table.id, table.version)
            parts += (table.column_ticks[key] for key in _VIEW_COLUMNS if key in table.column_ticks)
    return tuple(parts)


_VIEW_COLUMNS = [(ct, name) for ct in (Viewport, RenderTexture, RenderLayers) for name in ct.__fields__]


def _camera_views(world: World) -> tuple[CameraView, ...]:
    textures: list[CameraView] = []
    window: list[CameraView] = []
    plain: list[int] = []
    names: dict[str, int] = {}
    for batch in world.query(Camera, Transform, write=()):
        for eid in batch.entities:
            eid = int(eid)
            texture = _texture(world, eid)
            if texture is not None and texture[0] in names:
                raise UsageError(
                    f"two cameras (entities {names[texture[0]]} and {eid}) draw into a RenderTexture "
                    f"named {texture[0]!r}: give each its own name"
                )
            has_viewport = world.has(eid, Viewport)
            if texture is None and not has_viewport:
                plain.append(eid)
                continue
            view = _view(world, eid, texture)
            if texture is not None:
                names[texture[0]] = eid
                textures.append(view)
            else:
                window.append(view)
    main = _main_camera(world, plain, bool(window))
    if main is not None:
        window.append(CameraView(main, 0, (0.0, 0.0, 1.0, 1.0), _layers(world, main), None))
    if not window:
        raise UsageError(
            "no camera draws into the window: spawn one with Camera and Transform "
            "(a camera with a RenderTexture draws only into its texture)"
        )

    def order(view: CameraView) -> tuple[int, bool, int]:
        # the full-window camera first among its order: the backdrop the viewports draw over
        return view.order, view.entity != main, view.entity

    return tuple(sorted(textures, key=order)) + tuple(sorted(window, key=order))


def _main_camera(world: World, plain: list[int], others: bool) -> int | None:
    """The camera that draws the whole window: the only camera without a Viewport or a
    RenderTexture, or the one of several tagged ActiveCamera; None when there is none (or there
    are several, none tagged, and cameras with viewports cover the window instead)."""
    if len(plain) <= 1:
        return plain[0] if plain else None
    tagged = [eid for eid in plain if world.has(eid, ActiveCamera)]
    if len(tagged) == 1:
        return tagged[0]
    if others and not tagged:
        return None  # the extra cameras are controllers' or editors' spares: the viewports draw
    if not tagged:
        raise UsageError(
            f"{len(plain)} cameras have no Viewport or RenderTexture and none is tagged ActiveCamera: "
            "add ActiveCamera() to the one that draws the window, or give each a Viewport"
        )
    raise UsageError(f"{len(tagged)} cameras are tagged ActiveCamera: remove the tag from all but one")


def _texture(world: World, eid: int) -> tuple[str, int, int] | None:
    if not world.has(eid, RenderTexture):
        return None
    t = world.get(eid, RenderTexture)
    return str(t.name), int(t.width), int(t.height)


def _layers(world: World, eid: int) -> int:
    return int(world.get(eid, RenderLayers).mask) if world.has(eid, RenderLayers) else DEFAULT_LAYERS


def _view(world: World, eid: int, texture: tuple[str, int, int] | None) -> CameraView:
    if world.has(eid, Viewport):
        v = world.get(eid, Viewport)
        rect = (float(v.x), float(v.y), float(v.width), float(v.height))
        order = int(v.order)
    else:
        rect, order = (0.0, 0.0, 1.0, 1.0), 0
    return CameraView(eid, order, rect, _layers(world, eid), texture)


# per world: ((structure version, column versions), views)
_VIEWS: weakref.WeakKeyDictionary[Any, tuple[Any, tuple[CameraView, ...]]] = weakref.WeakKeyDictionary()
