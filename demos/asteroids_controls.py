"""The player's controls for asteroids: actions (the ActionMap resource) into the ShipControls
resource, each fixed step.

Default bindings (the user's `input-asteroids.json` in the config folder may rebind any action):
thrust W / S, up / down arrows, the left stick or the right trigger; turn A / D, left / right
arrows, the left stick or the d-pad; fire space, the left mouse button, A or the right bumper;
restart R or Start. The ship turns toward the mouse pointer when the mouse moves (the pointer
projected onto the game's plane through the camera) or toward where the right stick points, until
a turn key or the left stick turns it again.
"""

from __future__ import annotations

import math

import numpy as np

from ecs_engine.components import Camera, Transform
from ecs_engine.ecs import System, World
from ecs_engine.render.picking import pixel_ray
from ecs_engine.systems import ActionMap, InputState

from .asteroids_game import Ship, ShipControls

ACTIONS = {
    "thrust": ["s/w", "down/up", "-gamepad_left_y", "gamepad_right_trigger"],
    "turn": ["a/d", "left/right", "gamepad_left_x", "gamepad_dpad_left/gamepad_dpad_right"],  # +1: right
    "fire": ["space", "mouse_left", "gamepad_a", "gamepad_right_bumper"],
    "restart": ["r", "gamepad_start"],
    "aim_x": ["gamepad_right_x"],  # the right stick points where to face (screen right: +x)
    "aim_y": ["gamepad_right_y"],  # (stick down: +z, towards the camera)
}


def plane_point(world: World, pointer: tuple[float, float], viewport: tuple[float, float]) -> np.ndarray | None:
    """Where the ray through the pointer (pixels from the top left of a `viewport`-sized view of
    the active camera) meets the game's plane y = 0; None if it does not (or no view size)."""
    width, height = viewport
    if width <= 0 or height <= 0:
        return None
    origin, direction = pixel_ray(world, pointer[0], pointer[1], int(width), int(height))
    if direction[1] >= -1e-9:  # parallel to the plane or looking away from it
        return None
    return origin - direction * (origin[1] / direction[1])


class ShipControlSystem(System):
    """The ActionMap's actions (the UI's mouse and keyboard excepted, see ActionMap) into
    ShipControls; a mouse move or the right stick sets the direction to face."""

    def __init__(self) -> None:
        super().__init__(reads=[ActionMap, InputState, Ship, Camera, Transform], writes=[ShipControls], name="controls")
        self.mouse: tuple[float, float] | None = None  # where the pointer was when last looked at

    def run(self, world: World, dt: float) -> None:
        controls, actions = world.resources[ShipControls], ActionMap.of(world)
        controls.thrust = actions.axis("thrust")
        controls.turn = -actions.axis("turn")  # ShipControls turns left for +1
        controls.fire = actions.action_down("fire")
        controls.restart = controls.restart or actions.action_down("restart")  # a latch: the HUD sets it too
        stick = (actions.axis("aim_x"), actions.axis("aim_y"))
        if controls.turn != 0.0:
            controls.aim = None  # turning by hand ends aiming
        elif stick != (0.0, 0.0):
            controls.aim = stick
        elif (pointer := self._moved(actions)) is not None:
            self._aim_at(world, controls, pointer, actions.input.viewport)

    def _moved(self, actions: ActionMap) -> tuple[float, float] | None:
        """The pointer, if it moved since the last step (and the UI does not have the mouse). A
        move is seen by the position, not the frame's delta: a frame may run no fixed step."""
        pointer = actions.pointer()
        if pointer is None:
            return None
        before, self.mouse = self.mouse, pointer
        return pointer if before is not None and pointer != before else None

    @staticmethod
    def _aim_at(world: World, controls: ShipControls, pointer: tuple[float, float], viewport: tuple) -> None:
        ships = [b[Transform].position[0] for b in world.query(Transform, with_=(Ship,), write=()) if len(b)]
        target = plane_point(world, pointer, viewport)
        if not ships or target is None:
            return
        dx, dz = float(target[0] - ships[0][0]), float(target[2] - ships[0][2])
        if math.hypot(dx, dz) > 1e-6:
            controls.aim = (dx, dz)
