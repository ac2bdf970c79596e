"""Extract: every camera that draws this frame (components/camera_views.py), each with its
rectangle in pixels of its target and its matrices. Reads the cameras' Camera, Transform,
ActiveCamera, Viewport, RenderTexture and RenderLayers only."""

from __future__ import annotations

from dataclasses import dataclass

from ecs_engine.components.camera import ActiveCamera, Camera, RenderLayers, RenderTexture, Viewport
from ecs_engine.components.camera_views import CameraView, camera_views
from ecs_engine.components.transform import Transform

from ...ecs.structural import structural
from ...ecs.world import World
from ...maths.camera import check_positive
from .camera import CameraMatrices, camera_matrices_of

READS = (Camera, Transform, ActiveCamera, Viewport, RenderTexture, RenderLayers)


@dataclass(frozen=True)
class ViewData:
    """One camera's view of the frame. `rect` (x, y, width, height): pixels of its target,
    from the top left; `target_size`: the window's size, or its RenderTexture's; `camera`: its
    matrices, the projection's aspect that of `rect` (unless its Camera.aspect says otherwise)."""

    view: CameraView
    rect: tuple[int, int, int, int]
    target_size: tuple[int, int]
    camera: CameraMatrices

    @property
    def texture(self) -> str | None:
        """The RenderTexture's name, or None for the window."""
        return None if self.view.texture is None else self.view.texture[0]

    @property
    def layers(self) -> int:
        return self.view.layers


def extract_views(world: World, width: int, height: int) -> tuple[ViewData, ...]:
    """The views in drawing order (render textures first, then the window's by Viewport order),
    for a window of `width` x `height` pixels."""
    check_positive("width", width)
    check_positive("height", height)
    out = []
    for view in camera_views(world):
        size = (int(width), int(height)) if view.texture is None else (view.texture[1], view.texture[2])
        rect = view.pixels(*size)
        out.append(ViewData(view, rect, size, camera_matrices_of(world, view.entity, rect[2] / rect[3])))
    return tuple(out)


def several_views(world: World) -> bool:
    """Whether some camera may draw other than over the whole window: an entity has a Viewport
    or a RenderTexture (render/frame/views.py draws those; else the window's one camera as
    ever). Only a spawn, destroy, add or remove can change it: the answer is kept until one."""
    return bool(structural(world, "several_views", _has_views))


def _has_views(world: World) -> bool:
    return any(world.query(c, write=()).count() for c in (Viewport, RenderTexture))
