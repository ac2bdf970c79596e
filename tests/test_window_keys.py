"""GLFW key events to the fly camera (no window or display needed)."""

from __future__ import annotations


def test_glfw_keys_drive_the_fly_camera_with_the_seed_key_map():
    """The window's key events go through apply_key into InputState, which the fly camera reads."""
    import glfw
    import numpy as np

    from ecs_engine import Schedule, World
    from ecs_engine.app.window import apply_key, key_names
    from ecs_engine.components import Camera, FlyCamera, Transform
    from ecs_engine.systems import FlyCameraSystem, InputState

    names = key_names(glfw)
    assert {"left", "right", "up", "down", "w", "s", "a", "d", "e", "q", "space", "r", "left_shift", "f12"} <= set(
        names.values()
    )
    world = World()
    cam = world.spawn(Transform(), Camera(), FlyCamera(move_speed=2.0))
    keys = world.resources[InputState] = InputState()
    schedule = Schedule()
    schedule.add(FlyCameraSystem())
    apply_key(glfw, names, keys, glfw.KEY_W, glfw.PRESS)
    apply_key(glfw, names, keys, glfw.KEY_E, glfw.PRESS)
    apply_key(glfw, names, keys, glfw.KEY_E, glfw.REPEAT)
    apply_key(glfw, names, keys, glfw.KEY_UNKNOWN, glfw.PRESS)  # not a named key
    assert keys.pressed == {"w", "e"}
    schedule.run(world, 0.5)
    pos = world.get(cam, Transform).position
    assert pos[2] < 0 and pos[1] > 0  # forward is -Z, E is up
    apply_key(glfw, names, keys, glfw.KEY_W, glfw.RELEASE)
    apply_key(glfw, names, keys, glfw.KEY_E, glfw.RELEASE)
    apply_key(glfw, names, keys, glfw.KEY_LEFT, glfw.PRESS)
    schedule.run(world, 0.5)
    assert np.allclose(world.get(cam, Transform).position, pos)  # turning only
    assert world.get(cam, FlyCamera).yaw > 0  # left is counter-clockwise seen from above
