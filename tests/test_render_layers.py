"""RenderLayers: a camera draws the mesh entities whose layers share a bit with its own (rows
without the component are on layer 0); the extract stage leaves the others out of the frame's
chunks and set-aside rows (render/extract/chunks.py), and the picture shows only what it keeps."""

from __future__ import annotations

import math

import numpy as np
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.components import Camera, DirectionalLight, Mesh, RenderLayers, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, Materials, materials
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.extract.frame_data import FrameExtractor

W, H = 64, 32
LEFT, RIGHT = -1.2, 1.2


def _world(camera_mask: int | None, left_mask: int | None, right_mask: int | None, mesh: int = 0) -> World:
    """A red cube on the left and a green one on the right (each with RenderLayers when given a
    mask), seen by a camera with RenderLayers(camera_mask) when given."""
    world = World()
    red = materials(world).add(Material("red", "lambert", (1.0, 0.0, 0.0, 1.0)))
    green = materials(world).add(Material("green", "lambert", (0.0, 1.0, 0.0, 1.0)))
    for x, mask, material in ((LEFT, left_mask, red), (RIGHT, right_mask, green)):
        layers = () if mask is None else (RenderLayers(mask=mask),)
        world.spawn(Transform(position=(x, 0.0, 0.0)), Mesh(handle=mesh, material=material), *layers)
    cam = () if camera_mask is None else (RenderLayers(mask=camera_mask),)
    world.spawn(Transform(position=(0.0, 0.0, 4.0)), Camera(fov_y=math.radians(60.0)), *cam)
    world.spawn(Transform(rotation=look_rotation((0.0, 0.0, -1.0))), DirectionalLight(illuminance=3.0))
    return world


def _extracted(world: World, blend: np.ndarray | None = None) -> tuple[list[float], int]:
    """The x of every row the frame's chunks hold, and how many rows are set aside."""
    from ecs_engine.app.scenes import default_schedule

    default_schedule().run(world, 0.0)
    data = FrameExtractor(lambda: 1).extract(world, 2.0, 1, "none", set_aside=blend)
    xs = sorted(round(float(x), 3) for c in data.chunks for x in c.model[:, 0, 3])  # ModelMatrix [row, column]
    return xs, 0 if data.set_aside is None else len(data.set_aside)


def test_rows_outside_the_camera_s_layers_leave_the_chunks() -> None:
    assert _extracted(_world(None, None, None))[0] == [LEFT, RIGHT]  # nobody has layers: all drawn
    assert _extracted(_world(None, None, 0b10))[0] == [LEFT]  # the camera sees layer 0 only
    assert _extracted(_world(0b10, None, 0b10))[0] == [RIGHT]  # layer 1 only: the plain row goes
    assert _extracted(_world(0b11, None, 0b10))[0] == [LEFT, RIGHT]
    assert _extracted(_world(0b100, None, 0b10))[0] == []  # nothing in its layer


def test_a_change_of_layers_is_seen_the_next_frame() -> None:
    world = _world(None, None, 0b10)
    assert _extracted(world)[0] == [LEFT]
    (right,) = world.query(RenderLayers, write=()).entities()
    world.set(int(right), RenderLayers(mask=0b11))
    assert _extracted(world)[0] == [LEFT, RIGHT]


def test_blended_rows_outside_the_layers_are_not_set_aside() -> None:
    world = _world(None, None, 0b10)
    blend = np.zeros(len(Materials()) + 2, bool)
    blend[-1] = True  # the green material (the last added) is blended: the right cube
    assert _extracted(world, blend) == ([LEFT], 0)
    world.set(int(world.query(RenderLayers, write=()).entities()[0]), RenderLayers(mask=1))
    assert _extracted(world, blend) == ([LEFT], 1)


def _colours(img: np.ndarray) -> tuple[bool, bool]:
    """Whether the left half shows red and the right half green."""
    left, right = img[:, : W // 2].reshape(-1, 3), img[:, W // 2 :].reshape(-1, 3)
    red = bool(((left[:, 0] > 60) & (left[:, 1] < 30)).sum() > 20)
    green = bool(((right[:, 1] > 60) & (right[:, 0] < 30)).sum() > 20)
    return red, green


def test_the_picture_shows_only_the_camera_s_layers() -> None:
    with headless_gpu(W, H) as gpu:
        mesh = gpu.meshes.add(cube_mesh())
        assert _colours(render_world(gpu, _world(None, None, None, mesh))) == (True, True)
        assert _colours(render_world(gpu, _world(0b10, None, 0b10, mesh))) == (False, True)
        assert _colours(render_world(gpu, _world(None, 0b1, 0b10, mesh))) == (True, False)


def test_whether_any_entity_has_layers_is_asked_again_only_after_a_structural_change() -> None:
    from ecs_engine.ecs.structural import structural
    from ecs_engine.render.extract.frame_data import camera_layers

    asked = []

    def answer(world: World) -> int:
        asked.append(world.structure_version)
        return len(asked)

    world = _world(None, None, None)
    assert [structural(world, "test", answer) for _ in range(3)] == [1, 1, 1]  # kept: asked once
    (camera,) = world.query(Camera, write=()).entities()
    assert camera_layers(world) == 1  # nobody has layers: layer 0
    world.add(int(camera), RenderLayers(mask=0b110))  # a structural change
    assert structural(world, "test", answer) == 2 and len(asked) == 2
    assert camera_layers(world) == 0b110  # the camera's mask, seen at once
    world.set(int(camera), RenderLayers(mask=0b1))  # a value, not the structure: still read each frame
    assert camera_layers(world) == 0b1


def test_two_worlds_asked_in_turn_each_get_their_own_answer() -> None:
    from ecs_engine.render.extract.frame_data import camera_layers

    plain, layered = _world(None, None, None), _world(0b100, None, None)
    assert plain.structure_version == layered.structure_version  # the same count of changes
    assert [camera_layers(w) for w in (plain, layered, plain, layered)] == [1, 0b100, 1, 0b100]
