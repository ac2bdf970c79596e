"""Keyboard fly camera (the seed thesis's key map, Table 7.1), from the InputState resource
(input_state.py).

Left / Right arrows   yaw left / right (about world +Y)
Up / Down arrows      pitch up / down (about the camera's +X)
W / S                 forward / back along the view direction
A / D                 strafe left / right
E / Q                 up / down along world +Y
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ecs_engine.components.camera_control import FlyCamera
from ecs_engine.components.transform import Transform
from ecs_engine.ecs.schedule import System
from ecs_engine.ecs.world import World
from ecs_engine.maths.camera import yaw_pitch_quat

from .input_state import InputState

# Pitch stops this short of straight up/down: at the pole yaw and roll coincide and the view
# would flip when it is crossed.
PITCH_LIMIT = 0.5 * math.pi - 0.01
TAU = 2.0 * math.pi

KEYS = frozenset({"left", "right", "up", "down", "w", "s", "a", "d", "e", "q"})


class FlyInput(NamedTuple):
    """Key axes in {-1, 0, 1}: +turn = left, +tilt = up, +forward = W, +strafe = D (right),
    +lift = E (world up). Floats or per-camera arrays."""

    turn: float | np.ndarray = 0.0
    tilt: float | np.ndarray = 0.0
    forward: float | np.ndarray = 0.0
    strafe: float | np.ndarray = 0.0
    lift: float | np.ndarray = 0.0


NO_INPUT = FlyInput()  # every axis 0.0


def fly_input(state: InputState | None) -> FlyInput:
    """The axes for this frame; all zero (NO_INPUT) without input or while the UI has the keyboard."""
    if state is None or state.keyboard_captured_by_ui:
        return NO_INPUT
    keys = state.pressed
    if KEYS.isdisjoint(keys):
        return NO_INPUT  # the usual frame: none of its keys held

    def axis(plus: str, minus: str) -> float:
        return float(plus in keys) - float(minus in keys)

    return FlyInput(axis("left", "right"), axis("up", "down"), axis("w", "s"), axis("d", "a"), axis("e", "q"))


def wrap_angle(angle: np.ndarray) -> np.ndarray:
    """Angles mapped to (-pi, pi]; those already inside are returned bit-for-bit (the
    round trip through the remainder would round them, so a still camera would creep)."""
    inside = (angle > -math.pi) & (angle <= math.pi)
    return np.where(inside, angle, math.pi - np.remainder(math.pi - angle, TAU))


def fly_step(
    yaw: np.ndarray,
    pitch: np.ndarray,
    position: np.ndarray,
    rotation: np.ndarray,
    move_speed: np.ndarray,
    turn_speed: np.ndarray,
    axes: FlyInput,
    dt: float,
) -> None:
    """One frame for n cameras, in place: turn, then move along the new orientation.

    yaw, pitch, move_speed, turn_speed: (n,); position: (n, 3); rotation: (n, 4). The rotation
    is rebuilt from yaw and pitch (never integrated), so it stays exactly
    yaw_pitch_quat(yaw, pitch). The move direction is clamped to length 1, so diagonal keys
    are no faster than one key, while keys that oppose (E with W looking down) cancel smoothly.
    """
    step = turn_speed * dt
    yaw[...] = wrap_angle(yaw + step * axes.turn)
    pitch[...] = np.clip(pitch + step * axes.tilt, -PITCH_LIMIT, PITCH_LIMIT)
    rotation[...] = yaw_pitch_quat(yaw, pitch)
    if not any(np.any(a) for a in (axes.forward, axes.strafe, axes.lift)):
        return
    sy, cy = np.sin(yaw), np.cos(yaw)
    sp, cp = np.sin(pitch), np.cos(pitch)
    # forward = R @ (0, 0, -1), right = R @ (1, 0, 0) for R = yaw_pitch_quat(yaw, pitch)
    forward = np.stack([-sy * cp, sp, -cy * cp], axis=-1)
    right = np.stack([cy, np.zeros_like(cy), -sy], axis=-1)
    move = forward * np.asarray(axes.forward)[..., None] + right * np.asarray(axes.strafe)[..., None]
    move[..., 1] += axes.lift
    length = np.linalg.norm(move, axis=-1, keepdims=True)
    move /= np.maximum(length, 1.0)
    position += move * (move_speed * dt)[..., None]


class FlyCameraSystem(System):
    """Drives every entity with FlyCamera (and Transform) from the InputState resource."""

    def __init__(self) -> None:
        super().__init__(reads=[], writes=[Transform, FlyCamera], name="fly_camera")

    def run(self, world: World, dt: float) -> None:
        axes = fly_input(world.resources.get(InputState))
        query = world.query(Transform, FlyCamera)
        # no key held: only cameras whose FlyCamera was changed (yaw, pitch set by code) need
        # their rotation rebuilt; the others stay put, and their Transform takes no write tick,
        # so the transform system skips them too
        idle = axes is NO_INPUT or all(a == 0 if isinstance(a, float) else not np.any(a) for a in axes)
        batches = query.iter(changed=(FlyCamera,)) if idle else query
        for batch in batches:
            t = batch[Transform]
            fly = batch[FlyCamera]
            fly_step(fly.yaw, fly.pitch, t.position, t.rotation, fly.move_speed, fly.turn_speed, axes, float(dt))
