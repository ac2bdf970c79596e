"""Cameras (position and orientation come from the entity's Transform), where and what each
draws (Viewport, RenderTexture, RenderLayers: camera_views.py says how several cameras draw), which
one the player looks through, and the render origin that matrices are made relative to.

`active_camera` and `render_origin` are read by the stock systems and by the renderer alike,
so they live with the data they read rather than in either of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ecs_engine.ecs.schema import Component, Field
from ecs_engine.ecs.structural import structural
from ecs_engine.ecs.world import World
from ecs_engine.errors import UsageError

from .name import NAME_LENGTH
from .transform import LIMIT, SMALLEST, Transform

PERSPECTIVE = 0
ORTHOGRAPHIC = 1
MIN_FOV_Y = 1e-6  # radians
MAX_ASPECT = 1e3
# The largest orthographic view height: shadow cascades fitted to a wider view fail (their planes'
# normals fall under the 1e-12 that maths/culling.py's frustum_planes_many takes as degenerate).
MAX_VIEW_HEIGHT = 1e9


class Camera(Component):
    """Reverse-Z projection parameters. `far` may be +inf (an infinite far plane); NaN and
    -inf are rejected like any other non-finite value. `aspect` 0 means "follow the viewport".
    `height` is the view height of an orthographic camera.

    The ranges keep the float32 projection finite and non-zero where it must be: near and far
    within [SMALLEST, LIMIT] (far may also be +inf), height within [SMALLEST, MAX_VIEW_HEIGHT];
    fov_y at least MIN_FOV_Y (1/tan of half of it at most 2e6); aspect 0 or within
    [1/MAX_ASPECT, MAX_ASPECT]. A near plane of 1e300 made every frame print float32 overflow
    warnings."""

    projection = Field(np.uint8, default=PERSPECTIVE, maximum=ORTHOGRAPHIC)
    fov_y = Field(np.float64, default=np.radians(50.0), finite=True, minimum=MIN_FOV_Y, maximum=np.pi - MIN_FOV_Y)
    near = Field(np.float64, default=0.1, finite=True, minimum=SMALLEST, maximum=LIMIT)
    far = Field(np.float64, default=np.inf, finite=True, allow_posinf=True, minimum=SMALLEST)
    aspect = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=MAX_ASPECT)
    height = Field(np.float64, default=10.0, finite=True, minimum=SMALLEST, maximum=MAX_VIEW_HEIGHT)

    @classmethod
    def check(cls, values, who):
        near, far = np.broadcast_arrays(values["near"], values["far"])
        _refuse(near >= far, who, lambda r: f"Camera.near ({near[r]}) must be less than Camera.far ({far[r]})")
        too_far = np.isfinite(far) & (far > LIMIT)
        _refuse(too_far, who, lambda r: f"Camera.far must be <= {LIMIT:g} or +inf, got {far[r]:g}")
        aspect = values["aspect"].reshape(-1)
        narrow = (aspect != 0.0) & (aspect < 1.0 / MAX_ASPECT)
        _refuse(
            narrow,
            who,
            lambda r: f"Camera.aspect must be 0 (the viewport's) or >= {1.0 / MAX_ASPECT:g}, got {aspect[r]:g}",
        )


def _refuse(bad: np.ndarray, who: Any, what: Any) -> None:
    """ValueError naming the first row where `bad` holds (who: the entity, what: the rest)."""
    bad = np.atleast_1d(bad)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{who(row)}: {what(row)}")


#: The longest side of a render texture in pixels, for the RenderTexture component and
#: Textures.render_target alike (render_texture_size_error: one message): twice the largest layer
#: materials sample it from (render/assets/textures.py's MAX_TEXTURE_SIZE, 4096), so the blit into
#: the layer averages at most 2 x 2 pixels (a larger picture would be drawn to be thrown away), and
#: an image every Vulkan 1.3 roadmap device makes (maxImageDimension2D >= 8192).
MAX_RENDER_TEXTURE_SIDE = 8192
EDGE = 1e-9  # how far past the target's edge a viewport's float sum may land and still be its edge


class Viewport(Component):
    """The camera's rectangle of its target, as fractions from the top left, and its order."""

    x = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=1.0)
    y = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=1.0)
    width = Field(np.float64, default=1.0, finite=True, minimum=0.0, min_exclusive=True, maximum=1.0)
    height = Field(np.float64, default=1.0, finite=True, minimum=0.0, min_exclusive=True, maximum=1.0)
    order = Field(np.int32, default=0)

    @classmethod
    def check(cls, values, who):
        for start, size, axis in (("x", "width", "right"), ("y", "height", "bottom")):
            end = np.atleast_1d(np.asarray(values[start]) + np.asarray(values[size]))
            bad = np.flatnonzero(end > 1.0 + EDGE)
            if bad.size:
                row = int(bad[0])
                raise ValueError(
                    f"{who(row)}: Viewport.{start} + Viewport.{size} is {end[row]:g}: the viewport ends past "
                    f"the target's {axis} edge (fractions of the target, at most 1)"
                )


class RenderTexture(Component):
    """The camera draws into an image of its own, sampled by materials as texture `name`."""

    name = Field(f"U{NAME_LENGTH}", default="")
    width = Field(np.uint32, default=256)  # 1 to MAX_RENDER_TEXTURE_SIDE: `check` says so in one message
    height = Field(np.uint32, default=256)

    @classmethod
    def check(cls, values, who):
        names = np.atleast_1d(values["name"])
        empty = np.flatnonzero(np.char.str_len(names.astype(str)) == 0)
        if empty.size:
            raise ValueError(f"{who(int(empty[0]))}: RenderTexture.name is empty: materials sample it by name")
        names, widths, heights = np.broadcast_arrays(names, values["width"], values["height"])
        sizes = np.stack([widths.reshape(-1), heights.reshape(-1)])
        bad = np.flatnonzero(((sizes < 1) | (sizes > MAX_RENDER_TEXTURE_SIDE)).any(axis=0))
        if bad.size:
            row = int(bad[0])
            why = render_texture_size_error(str(names.reshape(-1)[row]), int(sizes[0, row]), int(sizes[1, row]))
            raise ValueError(f"{who(row)}: {why}")


def render_texture_size_error(name: str, width: Any, height: Any) -> str | None:
    """Why a render texture `name` of `width` x `height` pixels is refused, or None: the one
    message of the RenderTexture component (a ValueError, as every component's check raises)
    and of Textures.render_target (a UsageError)."""
    for what, value in (("width", width), ("height", height)):
        whole = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
        if not whole or not 1 <= value <= MAX_RENDER_TEXTURE_SIDE:
            return (
                f"render texture {name!r}: its {what} must be a whole number of pixels from 1 to "
                f"{MAX_RENDER_TEXTURE_SIDE}, not {value!r}"
            )
    return None


class RenderLayers(Component):
    """The layers a camera draws, or that a mesh entity is in (bit k = layer k)."""

    mask = Field(np.uint32, default=1)


class ActiveCamera(Component):
    """Tag: with several Camera entities, the one to render from (exactly one may carry it)."""


def active_camera(world: World) -> int:
    """The camera the player looks through (the render origin follows it, picking and the
    editor use it): of the cameras with Camera and Transform that do not draw into a
    RenderTexture, the only one, or else the one tagged ActiveCamera, or else (split screen) the
    first by Viewport order, then entity id. Raises UsageError when there is none or it is
    ambiguous. camera_views.py lists every camera that draws."""
    return structural(world, "active_camera", _active_camera)  # only the structure changes it


def _active_camera(world: World) -> int:
    cameras = world.query(Camera, Transform, without=(RenderTexture,), write=()).entities()
    if len(cameras) == 1:
        return int(cameras[0])
    if len(cameras) == 0:
        if len(world.query(Camera, Transform, write=()).entities()):
            raise UsageError("no camera draws into the window: every camera has a RenderTexture")
        raise UsageError("no camera: spawn an entity with Camera and Transform components")
    tagged = world.query(Camera, Transform, with_=(ActiveCamera,), without=(RenderTexture,), write=()).entities()
    if len(tagged) == 1:
        return int(tagged[0])
    if len(tagged) > 1:
        raise UsageError(f"{len(tagged)} cameras are tagged ActiveCamera: remove the tag from all but one")
    split = [
        (int(order), int(eid))
        for batch in world.query(Camera, Transform, Viewport, without=(RenderTexture,), write=())
        for eid, order in zip(batch.entities, batch[Viewport].order, strict=True)
    ]
    if split:
        return min(split)[1]
    raise UsageError(
        f"{len(cameras)} entities have Camera and Transform and none is tagged ActiveCamera: "
        "add ActiveCamera() to the one to render from"
    )


@dataclass
class RenderOrigin:
    """World resource: the float64 point that model matrices are made relative to before the
    cast to float32. RenderOriginSystem keeps it at the active camera (camera-relative
    rendering); `follow_camera=False` pins it (at the world origin: classic float32 world-space
    rendering, which jitters far from the origin; kept for comparison and measurement)."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    follow_camera: bool = True


def render_origin(world: World) -> np.ndarray:
    """The RenderOrigin resource's position (float64), or the world origin without one."""
    resource = world.resources.get(RenderOrigin)
    return np.zeros(3) if resource is None else np.asarray(resource.position, dtype=np.float64)
