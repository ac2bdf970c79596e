"""The editor's Physics window, shown while the world has a PhysicsWorld: pause the bodies, step
them one fixed step at a time, see what a step costs, and draw the colliders as wireframes over
the scene (the nearest MAX_WIREFRAMES)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..components import Camera, Transform, active_camera
from ..components.physics import BOX, PRIMITIVES, SPHERE, Collider
from ..maths.camera import rotation_matrix
from .editor_gizmo import gl_projection

MAX_WIREFRAMES = 500  # colliders drawn, the nearest the camera first: a line costs the UI's CPU
ROUND = 24  # segments of a drawn circle
COLOUR = 0xFF40E0FF  # ImGui's ABGR: a bright yellow-green


def collider_segments(position: np.ndarray, rotation: np.ndarray, shape: np.ndarray, size: np.ndarray) -> np.ndarray:
    """The wireframe of each collider as line segments (S, 2, 3) in world space: a box's twelve
    edges; a sphere's three great circles; a capsule's or cylinder's end circles and four sides."""
    segments = []
    for p, q, kind, s in zip(position, rotation, shape.tolist(), size):
        turn = rotation_matrix(q)[:3, :3]
        if kind == BOX:
            corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * s
            edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
            local = np.array([[corners[a], corners[b]] for a, b in edges])
        else:
            t = np.linspace(0.0, 2 * np.pi, ROUND + 1)
            ring = np.stack([np.cos(t), np.zeros_like(t), np.sin(t)], axis=1) * s[0]
            if kind == SPHERE:
                rings = [ring, ring[:, [1, 0, 2]], ring[:, [0, 2, 1]]]  # about y, x and z
                local = np.concatenate([np.stack([r[:-1], r[1:]], axis=1) for r in rings])
            else:  # capsule, cylinder: size[1] is the half height
                up = np.array([0.0, s[1], 0.0])
                ends = [ring + up, ring - up]
                sides = [[ring[k] + up, ring[k] - up] for k in (0, ROUND // 4, ROUND // 2, 3 * ROUND // 4)]
                local = np.concatenate([np.stack([r[:-1], r[1:]], axis=1) for r in ends] + [np.array(sides)])
        segments.append(local @ turn.T + p)
    return np.concatenate(segments) if segments else np.zeros((0, 2, 3))


def project(
    points: np.ndarray, eye: np.ndarray, eye_rotation: np.ndarray, projection: np.ndarray, rect: tuple
) -> tuple[np.ndarray, np.ndarray]:
    """Screen pixels (N, 2) of world `points` seen from the camera at `eye` with `eye_rotation`
    and OpenGL's `projection` (editor_gizmo.gl_projection) in `rect` (x0, y0, x1, y1), and which
    are in front of the camera."""
    view = rotation_matrix(eye_rotation)[:3, :3].T
    local = (points - eye) @ view.T
    clip = np.c_[local, np.ones(len(local))] @ projection.T
    front = clip[:, 3] > 1e-6
    ndc = clip[:, :2] / np.where(front, clip[:, 3], 1.0)[:, None]
    x0, y0, x1, y1 = rect
    screen = np.c_[x0 + (ndc[:, 0] + 1) / 2 * (x1 - x0), y0 + (1 - ndc[:, 1]) / 2 * (y1 - y0)]
    return screen, front


class PhysicsPanel:
    """The Physics window and the colliders' wireframes (see the module)."""

    def __init__(self) -> None:
        self.show_colliders = False

    @staticmethod
    def physics(world: Any) -> Any:
        from ..physics import PhysicsWorld  # (importing it needs no physics library)

        return world.resources.get(PhysicsWorld)

    def draw(self, imgui: Any, world: Any) -> None:
        physics = self.physics(world)
        if physics is None:
            return
        imgui.set_next_window_pos((680, 330), imgui.Cond_.first_use_ever.value)
        if imgui.begin("Physics")[0]:
            _, physics.paused = imgui.checkbox("paused", physics.paused)
            imgui.same_line()
            imgui.begin_disabled(not physics.paused)
            if imgui.button("step"):
                physics.step_once = True
            imgui.end_disabled()
            _, self.show_colliders = imgui.checkbox("show colliders", self.show_colliders)
            imgui.text(f"bodies     {len(physics.bodies):,}")
            imgui.text(f"steps      {physics.steps:,}")
            imgui.text(f"step       {physics.step_ms:.2f} ms")
            imgui.text(f"events     {physics.events_ms:.2f} ms")
        imgui.end()

    def draw_colliders(self, imgui: Any, world: Any, rect: tuple, drawlist: Any) -> int:
        """The nearest colliders' wireframes into `drawlist` over the scene in `rect`: how many
        lines were drawn."""
        if not self.show_colliders or self.physics(world) is None:
            return 0
        try:
            cam = active_camera(world)
        except Exception:  # no camera: nothing to draw them from
            return 0
        eye = world.get(cam, Transform)
        parts = [
            (b[Transform].position[keep], b[Transform].rotation[keep], b[Collider].shape[keep], b[Collider].size[keep])
            for b in world.query(Transform, Collider, write=())
            for keep in [np.isin(b[Collider].shape, PRIMITIVES)]  # (a mesh's shape is drawn already)
        ]
        if not parts:
            return 0
        position, rotation, shape, size = (np.concatenate(column) for column in zip(*parts))
        nearest = np.argsort(np.linalg.norm(position - eye.position, axis=1))[:MAX_WIREFRAMES]
        segments = collider_segments(position[nearest], rotation[nearest], shape[nearest], size[nearest])
        return draw_segments(imgui, world, cam, segments, rect, drawlist, COLOUR, 1.0)


def draw_segments(
    imgui: Any, world: Any, cam: int, segments: np.ndarray, rect: tuple, drawlist: Any, colour: int, thickness: float
) -> int:
    """World-space line `segments` (S, 2, 3) seen from camera `cam`, drawn into `drawlist` (None:
    the background's) over the scene in `rect`; a line with an end behind the eye is left out.
    How many were drawn."""
    eye = world.get(cam, Transform)
    x0, y0, x1, y1 = rect
    projection = gl_projection(world.get(cam, Camera), (x1 - x0) / max(y1 - y0, 1.0))
    screen, front = project(segments.reshape(-1, 3), eye.position, eye.rotation, projection, rect)
    both = np.asarray(front.reshape(-1, 2).all(axis=1))
    target = drawlist if drawlist is not None else imgui.get_background_draw_list()
    drawn = 0
    for a, b in screen.reshape(-1, 2, 2)[both].tolist():
        target.add_line(imgui.ImVec2(*a), imgui.ImVec2(*b), colour, thickness)
        drawn += 1
    return drawn
