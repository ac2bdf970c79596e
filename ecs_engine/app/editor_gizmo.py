"""The editor's transform gizmo (ImGuizmo, shipped with imgui-bundle) over the selected entity:
translate, rotate or scale it with the mouse in the scene, each drag one undoable step.

ImGuizmo works in OpenGL conventions: column-major float[16], a clip space with y up and depth
-1..1. The engine's camera is reverse-Z Vulkan; the gizmo gets an OpenGL projection of the same
field of view (or orthographic height), which puts every point on the same pixel. Positions are
taken relative to the camera, in float64 before the cast, so the gizmo stays exact far from the
origin. A result is split back into position, rotation (a unit quaternion from the normalised
columns; a mirrored matrix keeps its sign in the x scale) and scale.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..components import ORTHOGRAPHIC, Camera, Transform, active_camera
from ..ecs.world import World
from ..maths.camera import rotation_matrix
from ..maths.decompose import decompose
from ..maths.transform import compose_numpy
from .editor_history import History

OPERATIONS = ("translate", "rotate", "scale")


def gl_projection(camera: Any, aspect: float) -> np.ndarray:
    """An OpenGL projection (y up, depth -1..1) matching the camera's view of the scene; an
    infinite far plane becomes 10^5 near planes (the gizmo only needs directions there)."""
    near = float(camera.near)
    far = float(camera.far) if math.isfinite(float(camera.far)) else near * 1e5
    aspect = float(camera.aspect) or aspect
    p = np.zeros((4, 4))
    if int(camera.projection) == ORTHOGRAPHIC:
        half_h = float(camera.height) / 2.0
        p[0, 0], p[1, 1] = 1.0 / (half_h * aspect), 1.0 / half_h
        p[2, 2], p[2, 3], p[3, 3] = -2.0 / (far - near), -(far + near) / (far - near), 1.0
        return p
    f = 1.0 / math.tan(float(camera.fov_y) / 2.0)
    p[0, 0], p[1, 1] = f / aspect, f
    p[2, 2], p[2, 3], p[3, 2] = -(far + near) / (far - near), -2.0 * far * near / (far - near), -1.0
    return p


def column_major(m: np.ndarray) -> list[float]:
    return [float(v) for v in np.asarray(m, np.float64).T.ravel()]


def from_column_major(values: Any) -> np.ndarray:
    return np.array([float(values[i]) for i in range(16)]).reshape(4, 4).T


class Gizmo:
    """Draws and applies the gizmo for one selected entity each frame."""

    def __init__(self) -> None:
        from imgui_bundle import imgui, imguizmo

        self.imgui = imgui
        self.g = imguizmo.im_guizmo
        self.module = imguizmo
        self.operation = "translate"
        self.local = False  # rotate and translate along the entity's own axes
        self.used = False  # the gizmo took the mouse this frame (the scene click must not pick)

    def draw(
        self,
        world: World,
        entity: int,
        history: History,
        rect: tuple[float, float, float, float],
        drawlist: Any = None,
    ) -> None:
        """The gizmo over `entity`, the scene shown in `rect` (x0, y0, x1, y1 pixels), drawn into
        `drawlist` (the Scene window's: clipped to it, over its image) or the background's."""
        g = self.g
        g.begin_frame()
        self.used = False
        try:
            cam_id = active_camera(world)
        except Exception:  # no camera: nothing to place the gizmo with
            return
        camera = world.get(cam_id, Camera)
        eye = world.get(cam_id, Transform)
        g.set_orthographic(int(camera.projection) == ORTHOGRAPHIC)
        x0, y0, x1, y1 = (float(v) for v in rect)
        g.set_rect(x0, y0, x1 - x0, y1 - y0)
        # without a Scene window: under the panels, over the scene drawn under the whole window;
        # with no list given, ImGuizmo draws into the current window: outside any window,
        # ImGui's fallback "Debug" window, which then shows and clips the gizmo to itself
        g.set_drawlist(drawlist if drawlist is not None else self.imgui.get_background_draw_list())
        view = np.eye(4)
        view[:3, :3] = rotation_matrix(eye.rotation)[:3, :3].T  # the camera at the origin
        t = world.get(entity, Transform)
        model = np.zeros((1, 4, 4))  # float64, relative to the camera
        compose_numpy(
            np.asarray([t.position], np.float64),
            np.asarray([t.rotation], np.float64),
            np.asarray([t.scale], np.float64),
            np.asarray(eye.position, np.float64),
            model,
        )
        model = model[0]
        matrix = self.module.im_guizmo.Matrix16(column_major(model))
        op = getattr(g.OPERATION, self.operation)
        mode = g.MODE.local if self.local or self.operation == "scale" else g.MODE.world
        changed = g.manipulate(
            self.module.im_guizmo.Matrix16(column_major(view)),
            self.module.im_guizmo.Matrix16(column_major(gl_projection(camera, (x1 - x0) / max(y1 - y0, 1.0)))),
            op,
            mode,
            matrix,
        )
        self.used = bool(g.is_using() or g.is_over())
        if g.is_using() or changed:  # the release frame may still move it: the same step
            history.begin(("gizmo", entity), world, entity, Transform)
        else:
            history.end(("gizmo", entity))
        if changed:
            position, rotation, scale = decompose(from_column_major(matrix.values))
            history.set(
                world,
                entity,
                Transform,
                position=np.asarray(eye.position, np.float64) + position,
                rotation=rotation,
                scale=scale,
            )
