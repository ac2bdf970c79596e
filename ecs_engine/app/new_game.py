"""`ecs-engine new NAME`: a starter game folder, NAME/game.py, that runs as it is written
(`ecs-engine play NAME`, or `python NAME/game.py`): a cube the arrow keys turn, a light and a
camera, through App. An existing folder (or file) of that name is never touched."""

from __future__ import annotations

from pathlib import Path

from ..errors import UsageError

TEMPLATE = '''\
"""{title}: a starter game. Run it with `ecs-engine play {folder}` (add --headless --frames 60
--screenshot shot.png to draw it without a window), or `python {folder}/game.py`.

A game is components (data), systems (functions over the world) and a build(app) that adds
them to an App. docs/app.md has the rest: meshes, materials, lights, input, the window, time."""

import numpy as np

from ecs_engine import App, Component, DefaultPlugins, Field
from ecs_engine.components import AngularVelocity, Camera, DirectionalLight, Mesh, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, Meshes, cube_mesh, materials
from ecs_engine.systems import InputState


class Spinner(Component):
    """What the arrow keys turn: its speed in radians a second."""

    speed = Field(np.float64, default=1.0, finite=True)


def setup(world, dt):
    """Once, before the first frame: an orange cube, a light and a camera looking at it."""
    cube = world.resources[Meshes].add(cube_mesh())
    orange = materials(world).add(Material("orange", base_color=(1.0, 0.45, 0.1, 1.0), roughness=0.4))
    world.spawn(Transform(), Mesh(handle=cube, material=orange), AngularVelocity(), Spinner())
    world.spawn(Transform(rotation=look_rotation((-0.3, -1.0, -0.5))), DirectionalLight(illuminance=1.5))
    world.spawn(Transform(position=(0.0, 1.2, 3.0), rotation=look_rotation((0.0, -1.2, -3.0))), Camera())


def steer(world, dt):
    """Every frame: left and right change the spin (MotionPlugin turns the cube by it)."""
    keys = world.resources[InputState]
    turn = float(keys.down("right")) - float(keys.down("left"))
    for batch in world.query(Spinner, AngularVelocity):
        batch[Spinner].speed += turn * 2.0 * dt
        batch[AngularVelocity].angular[:, 1] = batch[Spinner].speed


def build(app):
    app.title = "{title}"
    app.add_plugins(DefaultPlugins)  # window, rendering, input, time, motion, transforms...
    app.add_startup_systems(setup)
    app.add_systems("update", steer)


if __name__ == "__main__":
    app = App()
    build(app)
    app.run()
'''


def write_game(name: str) -> int:
    """Write NAME/game.py; UsageError (nothing written) for a folder or file already there."""
    folder = Path(name)
    if not folder.name or folder.name in (".", ".."):
        raise UsageError(f"new: {name!r} is not a folder name")
    if folder.exists() or folder.is_symlink():
        raise UsageError(f"new: {folder} exists already; choose another name (nothing was written)")
    if not folder.parent.is_dir():
        raise UsageError(f"new: folder {folder.parent} does not exist")
    title = folder.name.replace("_", " ").replace("-", " ").strip().title() or folder.name
    folder.mkdir()
    (folder / "game.py").write_text(TEMPLATE.format(title=title, folder=name))
    print(f"wrote {folder / 'game.py'}; play it with: ecs-engine play {name}")
    return 0
