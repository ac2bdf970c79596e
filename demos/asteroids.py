"""Asteroids: a ship on a wrapping field of thousands of spinning rocks (up to 100,000 as the
levels rise), flown with the keyboard, mouse or a gamepad (through actions,
asteroids_controls.py) or by a bot, with sound (asteroids_sound.py). The game itself is
components and systems (asteroids_game.py, asteroids_bot.py); this module makes its meshes, materials, light, camera and
schedule, and is a game module: `build(app)` makes the App `ecs-engine play asteroids` runs, with
the game's own options (`add_arguments`: --autoplay, --seed, --level)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

import numpy as np

from ecs_engine import App, World
from ecs_engine.components import Camera, DirectionalLight, Transform
from ecs_engine.ecs import Schedule, System
from ecs_engine.errors import UsageError
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, MeshData, cone_mesh, materials, sphere_mesh
from ecs_engine.systems import ActionMap

from .asteroids_bot import BotSystem
from .asteroids_controls import ACTIONS, ShipControlSystem
from .asteroids_game import (
    LEVEL_ASTEROIDS,
    CollisionSystem,
    DamageSystem,
    FollowCameraSystem,
    Game,
    LevelSystem,
    LifetimeSystem,
    RestartSystem,
    ShipControls,
    ShipSystem,
    WrapSystem,
    start,
)
from .asteroids_hud import draw_hud, summary
from .asteroids_sound import SoundSystem, start_sound

__all__ = ["ACTIONS", "LEVELS", "ShipControls", "add_arguments", "build", "build_world", "controls", "draw_hud"]
__all__ += ["schedule", "summary"]

LEVELS = len(LEVEL_ASTEROIDS)  # `play --level` goes from 1 to this


def rock_mesh(seed: int = 5) -> MeshData:
    """A lumpy unit-diameter rock: a coarse sphere pushed in and out along its normals."""
    base = sphere_mesh(segments=12, rings=8, radius=0.5)
    rng = np.random.default_rng(seed)
    positions = base.positions.astype(np.float64)
    # the same bump for vertices at one place (the seam's copies), so the rock stays closed
    keys = np.round(positions, 4)
    _, where, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    bumps = rng.uniform(0.8, 1.15, len(where))[inverse.reshape(-1)]
    positions *= bumps[:, None]
    return MeshData.from_arrays(positions.astype(np.float32), base.normals, base.indices, "rock")


def ship_mesh() -> MeshData:
    """A dart pointing down -Z (the ship's forward)."""
    cone = cone_mesh(segments=3, radius=0.7, height=1.8)
    turn = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # +Y (the tip) to -Z
    return MeshData.from_arrays(
        (cone.positions @ turn.T).astype(np.float32), (cone.normals @ turn.T).astype(np.float32), cone.indices, "ship"
    )


def build_world(
    world: World,
    add_mesh: Callable[[MeshData], int],
    path: str | None = None,
    seed: int = 1,
    autoplay: bool = False,
    level: int = 1,
    physics: bool = False,
) -> None:
    looks = materials(world)
    game = Game(
        seed=int(seed),
        first_level=int(level),
        meshes={"rock": add_mesh(rock_mesh()), "ship": add_mesh(ship_mesh()), "shot": add_mesh(sphere_mesh(8, 6))},
        materials={
            "rock": looks.add(Material("rock", "cook_torrance", (0.45, 0.4, 0.36, 1.0), roughness=0.9)),
            "ship": looks.add(
                Material(
                    "ship",
                    "cook_torrance",
                    (0.3, 0.6, 1.0, 1.0),
                    metallic=0.1,
                    roughness=0.4,
                    emissive=(0.05, 0.12, 0.3),
                )
            ),
            "shot": looks.add(Material("shot", "unlit", (1.0, 0.9, 0.3, 1.0), emissive=(4.0, 3.0, 0.8))),
        },
    )
    if physics:
        from .asteroids_physics import bodies

        game.bodies = bodies
    world.resources[Game] = game
    world.resources[ShipControls] = ShipControls()
    if ActionMap not in world.resources:  # `play` puts the user's bindings there first
        world.resources[ActionMap] = ActionMap(ACTIONS)
    world.spawn(Transform(rotation=look_rotation((0.3, -1.0, -0.4))), DirectionalLight(illuminance=0.9))
    world.spawn(
        Transform(position=FollowCameraSystem.OFFSET, rotation=look_rotation(-FollowCameraSystem.OFFSET)),
        Camera(fov_y=math.radians(50.0), near=0.5, far=2000.0),
    )
    start(world, game)


def controls() -> ShipControlSystem:
    """The player's controls: the ActionMap's actions (bindings: ACTIONS) into ShipControls."""
    return ShipControlSystem()


def game_systems(
    autoplay: bool = False, controls: System | None = None, sound: bool = False
) -> dict[str, list[System]]:
    """The game's own systems by stage: controls (the bot, or `controls`, a system filling
    ShipControls from the input), the ship, motion, wrap, lifetimes, collisions, (with `sound`:
    its sounds, asteroids_sound.py), damage, levels, restart in the fixed step; the camera per
    frame."""
    from ecs_engine.systems import MotionSystem

    fixed: list[System] = [BotSystem()] if autoplay else [controls] if controls is not None else []
    fixed += [ShipSystem(), MotionSystem(), WrapSystem(), LifetimeSystem(), CollisionSystem()]
    fixed += [SoundSystem()] if sound else []  # (before the damage destroys what was hit)
    fixed += [DamageSystem(), LevelSystem(), RestartSystem()]
    return {"fixed": fixed, "update": [FollowCameraSystem()]}


def add_game_systems(app: App, autoplay: bool, controls: System | None, physics: bool = False) -> None:
    """game_systems (with sound) into `app`; with `physics`, the PhysicsPlugin's step and the
    ship's contacts where MotionSystem moved everything else (asteroids_physics.py)."""
    from ecs_engine.systems import MotionSystem

    for stage, systems in game_systems(autoplay, controls, sound=True).items():
        for system in systems:
            app.add_systems(stage, system)
            if physics and isinstance(system, MotionSystem):  # (the bodies move where the rest did)
                from .asteroids_physics import ShipContactSystem, physics_plugin

                app.add_plugins(physics_plugin())
                app.add_systems(stage, ShipContactSystem())


def schedule(autoplay: bool = False, controls: System | None = None, sound: bool = False) -> Schedule:
    """The game's systems (game_systems), then the stock render origin and matrices (and, with
    `sound`, AudioSystem: the world needs the Audio resource and start_sound)."""
    from ecs_engine.audio import AudioSystem
    from ecs_engine.systems import RenderOriginSystem, TransformSystem

    steps = Schedule(("fixed", "update", "post_update"))
    for stage, systems in game_systems(autoplay, controls, sound).items():
        for system in systems:
            steps.add(system, stage)
    steps.add(RenderOriginSystem(), "post_update")
    steps.add(TransformSystem(), "post_update")
    if sound:
        steps.add(AudioSystem(), "post_update")
    return steps


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The game's own command-line options (`ecs-engine play asteroids --level 3`)."""
    from ecs_engine.app.cli import non_negative_int, positive_int

    parser.add_argument("--autoplay", action="store_true", help="a bot plays (reproducible with --seed)")
    parser.add_argument(
        "--seed", type=non_negative_int, default=1, help="the game's random seed, 0 or more (default 1)"
    )
    parser.add_argument(
        "--level",
        type=positive_int,
        default=1,
        help=f"the level to start at, 1 to {LEVELS} ({LEVELS}: 100,000 asteroids)",
    )
    parser.add_argument(
        "--physics",
        action="store_true",
        help="asteroids bounce off one another and the ship (the physics extra: pip install 'ecs_engine[physics]')",
    )


def build(app: App) -> None:
    """The game as an App: the stock plugins it uses (no fly camera, hierarchy or interpolated
    motion: its own systems move everything), its HUD, its score line, its actions."""
    from ecs_engine.app.plugins import CameraControlPlugin, DefaultPlugins, HierarchyPlugin, MotionPlugin, TimePlugin
    from ecs_engine.audio import AudioPlugin
    from ecs_engine.render import Meshes

    options = app.options
    seed, level = int(getattr(options, "seed", 1)), int(getattr(options, "level", 1))
    autoplay, physics = bool(getattr(options, "autoplay", False)), bool(getattr(options, "physics", False))
    if not 1 <= level <= LEVELS:
        raise UsageError(f"--level {level}: asteroids has levels 1 to {LEVELS}")
    app.title = "Asteroids"
    app.add_plugins(DefaultPlugins.without(TimePlugin, MotionPlugin, CameraControlPlugin, HierarchyPlugin))
    app.add_plugins(AudioPlugin())
    if not autoplay:  # the bot needs no bindings (build_world puts the defaults there)
        app.add_actions(ACTIONS)

    def setup(world: World, dt: float) -> None:
        build_world(world, world.resources[Meshes].add, seed=seed, autoplay=autoplay, level=level, physics=physics)
        start_sound(world)

    app.add_startup_systems(setup)
    add_game_systems(app, autoplay, None if autoplay else controls(), physics)
    app.add_ui(draw_hud)
    app.set_summary(summary)
