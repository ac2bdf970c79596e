"""Asteroids through the action map (demos/asteroids_controls.py): a scripted mouse move turns
the ship toward the pointer on the game's plane, a fake gamepad turns, thrusts and fires it,
and in a run the HUD keeps the mouse while ImGui wants it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_asteroids import Meshes
from test_input_gamepad import raw

from ecs_engine import World
from ecs_engine.app.gamepads import GamepadPoller, reading
from ecs_engine.app.input_script import read_script
from ecs_engine.components import Transform, Velocity
from ecs_engine.demos import asteroids
from ecs_engine.demos.asteroids_controls import plane_point
from ecs_engine.demos.asteroids_game import Asteroid, Game, Ship, ShipControls
from ecs_engine.ecs.timestep import FixedTimestep
from ecs_engine.render.frame.camera import camera_matrices
from ecs_engine.systems import InputState

WIDTH, HEIGHT = 640, 400


def player_world():
    """The game with the player's controls, the field cleared (nothing to hit the ship)."""
    world = World()
    asteroids.build_world(world, Meshes().add, seed=1)
    world.destroy(world.query(Asteroid).entities())
    state = world.resources[InputState] = InputState(viewport=(float(WIDTH), float(HEIGHT)))
    schedule = asteroids.schedule(controls=asteroids.controls())
    return world, schedule, state


def step(world, schedule, state, script=None, frames=1, start=0):
    clock = FixedTimestep(1 / 60)
    for frame in range(start, start + frames):
        if script is not None:
            script.apply(frame, state)
        schedule.run_frame(world, 1 / 60, clock)
        state.end_frame()


def pixel_of(world, point) -> tuple[float, float]:
    """Where a world point is drawn in a WIDTH x HEIGHT view (the inverse of picking's pixel_ray)."""
    cam = camera_matrices(world, WIDTH / HEIGHT)
    relative = np.asarray(point, np.float64) - cam.position
    clip = cam.projection.astype(np.float64) @ np.append(cam.view[:3, :3].astype(np.float64) @ relative, 1.0)
    ndc = clip[:2] / clip[3]
    return float((ndc[0] + 1.0) * WIDTH / 2.0), float((ndc[1] + 1.0) * HEIGHT / 2.0)


def ship(world):
    entity = int(world.query(Ship).entities()[0])
    return world.get(entity, Ship), world.get(entity, Transform)


def facing(heading: float) -> np.ndarray:
    return np.array([-math.sin(heading), -math.cos(heading)])  # (x, z): heading 0 looks down -Z


@pytest.mark.parametrize("target", [(10.0, 0.0, 0.0), (-6.0, 0.0, 8.0), (3.0, 0.0, -12.0)])
def test_a_scripted_mouse_move_turns_the_ship_toward_the_pointer(tmp_path, target):
    world, schedule, state = player_world()
    step(world, schedule, state)  # the camera settles over the ship
    x, y = pixel_of(world, target)
    assert np.allclose(plane_point(world, (x, y), state.viewport), target, atol=1e-6)  # the pointer's ray
    path = tmp_path / "mouse.txt"
    path.write_text(f"2 move {x!r} {y!r}\n")
    step(world, schedule, state, read_script(path), frames=90, start=1)  # 1.5 s: time for a half turn
    heading = float(ship(world)[0].heading)
    at = ship(world)[1].position[[0, 2]]
    want = np.array([target[0], target[2]]) - at
    assert facing(heading) @ (want / np.linalg.norm(want)) > 0.9999  # faces the pointer
    assert world.resources[ShipControls].aim is not None
    state.press("a")  # a turn key takes over from the mouse
    step(world, schedule, state, frames=10)
    assert world.resources[ShipControls].aim is None and float(ship(world)[0].heading) > heading


def test_a_mouse_move_over_the_ui_does_not_turn_the_ship():
    world, schedule, state = player_world()
    step(world, schedule, state)
    state.mouse_captured_by_ui = True
    state.move_mouse(*pixel_of(world, (10.0, 0.0, 0.0)))
    step(world, schedule, state, frames=30)
    assert world.resources[ShipControls].aim is None and float(ship(world)[0].heading) == 0.0


def test_a_fake_gamepad_turns_thrusts_and_fires_and_a_lost_pad_stops():
    world, schedule, state = player_world()
    poller = GamepadPoller()
    game = world.resources[Game]
    pad = reading(raw(("gamepad_a",), left_x=1.0, right_trigger=1.0))  # stick right, trigger in, A held
    for _ in range(30):
        poller.update(state, {0: pad})
        step(world, schedule, state)
    heading = float(ship(world)[0].heading)
    assert heading == pytest.approx(-3.5 * 30 / 60)  # full right turn rate for 30 steps
    speed = np.linalg.norm(world.get(int(world.query(Ship).entities()[0]), Velocity).linear)
    assert speed > 5.0 and game.shots > 0
    shots = game.shots
    for _ in range(30):
        poller.update(state, {})  # unplugged
        step(world, schedule, state)
    assert float(ship(world)[0].heading) == heading and game.shots == shots
    assert "gamepad_a" not in state.pressed
    pad = reading(raw(right_x=0.0, right_y=1.0))  # the right stick points down the screen: +Z
    for _ in range(90):
        poller.update(state, {1: pad})
        step(world, schedule, state)
    assert facing(float(ship(world)[0].heading)) @ np.array([0.0, 1.0]) > 0.9999
