"""The physics playground (`ecs-engine play physics`, the `physics` extra): a pile of boxes to
knock down, a row of dominoes, a chain of hinged links, a tower with a ragdoll standing by it,
a second ragdoll falling onto a ramp and a character walking a loop through it all; fly the
camera (WASD and the mouse) and shoot balls where it looks (the left mouse button or space).
`--autoplay` shoots on its own, one ball every half second from where the camera stands. A
game module, as asteroids is."""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

import numpy as np

from ecs_engine import App, World
from ecs_engine.components import Camera, DirectionalLight, FlyCamera, Mesh, Transform, Velocity
from ecs_engine.components.physics import BOX, HINGE, SPHERE, STATIC, CharacterController, Collider, Joint, RigidBody
from ecs_engine.ecs import System
from ecs_engine.maths.camera import look_rotation, rotation_matrix
from ecs_engine.render import Material, cube_mesh, cylinder_mesh, materials, sphere_mesh
from ecs_engine.systems import ActionMap

from .physics_ragdoll import spawn_ragdoll

ACTIONS = {"shoot": ["mouse_left", "space", "gamepad_right_bumper"]}
BALL_SPEED = 30.0  # m/s
BALL_RADIUS = 0.35
BALLS_KEPT = 200  # the oldest ball goes when one more is shot
CHAIN_LINKS, LINK = 10, 0.8  # the hanging chain's links and their length (m)
WALK_LOOP = ((-8.0, 4.0), (20.0, 4.0), (20.0, -16.0), (-8.0, -16.0))  # the walker's corners (x, z)
WALK_SPEED, JUMP_SPEED = 4.0, 5.0  # m/s


@dataclass(frozen=True)
class BallLook:
    """The shot balls' mesh and material (a resource made with the world)."""

    mesh: int
    material: int


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--autoplay", action="store_true", help="shoot a ball every half second on its own")
    parser.add_argument("--pile", type=int, default=1000, help="boxes in the pile (default 1,000)")


def build(app: App) -> None:
    from ecs_engine.app.plugins import DefaultPlugins
    from ecs_engine.physics import PhysicsPlugin
    from ecs_engine.render import Meshes

    autoplay, pile = getattr(app.options, "autoplay", False), getattr(app.options, "pile", 1000)
    app.title = "Physics playground"
    app.add_plugins(DefaultPlugins, PhysicsPlugin())
    app.add_actions(ACTIONS)

    def setup(world: World, dt: float) -> None:
        build_world(world, world.resources[Meshes].add, pile)

    app.add_startup_systems(setup)
    app.add_systems("fixed", ShootSystem(autoplay), WalkerSystem())


def build_world(world: World, add_mesh: object, pile: int = 1000) -> None:
    """The playground's bodies, meshes, materials, light and camera."""
    cube, ball = add_mesh(cube_mesh()), add_mesh(sphere_mesh(radius=BALL_RADIUS))  # type: ignore[operator]
    looks = materials(world)
    ground = looks.add(Material("ground", "cook_torrance", (0.35, 0.37, 0.4, 1.0), roughness=0.95))
    crate = looks.add(Material("crate", "cook_torrance", (0.75, 0.5, 0.25, 1.0), roughness=0.7))
    domino = looks.add(Material("domino", "cook_torrance", (0.9, 0.9, 0.85, 1.0), roughness=0.4))
    red = looks.add(Material("ball", "cook_torrance", (0.8, 0.1, 0.1, 1.0)))
    world.resources[BallLook] = BallLook(ball, red)

    def static_box(position: tuple, half: tuple, rotation: tuple = (0.0, 0.0, 0.0, 1.0)) -> None:
        scale = tuple(2 * h for h in half)
        world.spawn(
            Transform(position=position, rotation=rotation, scale=scale),
            Mesh(handle=cube, material=ground),
            RigidBody(kind=STATIC),
            Collider(shape=BOX, size=half),
        )

    static_box((0.0, -0.5, 0.0), (60.0, 0.5, 60.0))
    tilt = math.radians(15.0)
    static_box((-14.0, 2.0, -6.0), (6.0, 0.25, 2.0), (0.0, 0.0, math.sin(tilt / 2), math.cos(tilt / 2)))
    # the pile: boxes in a block, apart and turned a little at random, falling into a heap
    side = max(1, round(pile ** (1 / 3)))
    i = np.arange(pile)
    rng = np.random.default_rng(7)
    grid = np.c_[i % side, i // (side * side), (i // side) % side] * 1.4 + rng.uniform(-0.2, 0.2, (pile, 3))
    where = grid + (6.0 - side * 0.7, 3.0, -side * 0.7)
    turns = rng.normal(size=(pile, 4))
    turns /= np.linalg.norm(turns, axis=1)[:, None]
    crates = Transform(position=where, rotation=turns)
    world.spawn_batch(pile, crates, Mesh(handle=cube, material=crate), RigidBody(), Collider())
    # dominoes in a row, the first leaning onto the second
    for k in range(24):
        lean = (0.0, 0.0, math.sin(-0.2), math.cos(-0.2)) if k == 0 else (0.0, 0.0, 0.0, 1.0)
        world.spawn(
            Transform(position=(-22.0 + k * 0.9, 1.0, 14.0), rotation=lean, scale=(0.2, 2.0, 1.0)),
            Mesh(handle=cube, material=domino),
            RigidBody(mass=2.0),
            Collider(shape=BOX, size=(0.1, 1.0, 0.5), friction=0.6),
        )
    # a chain of hinged links hanging from a beam, swung at the start (its links pass through
    # each other's ends: category 8, which their mask leaves out)
    top = world.spawn(
        Transform(position=(14.0, 12.0, 0.0), scale=(0.4, 0.4, 0.4)),
        Mesh(handle=cube, material=ground),
        RigidBody(kind=STATIC),
        Collider(shape=BOX, size=(0.2, 0.2, 0.2), category=8, mask=1),
    )
    above = top
    for k in range(CHAIN_LINKS):
        y = 12.0 - 0.2 - LINK * (k + 0.5)
        above = world.spawn(
            Transform(position=(14.0, y, 0.0), scale=(0.3, LINK, 0.3)),
            Mesh(handle=cube, material=domino),
            RigidBody(mass=1.0),
            Collider(shape=BOX, size=(0.15, LINK / 2, 0.15), category=8, mask=1),
            Joint(kind=HINGE, other=above, pivot=(14.0, y + LINK / 2, 0.0), axis=(0.0, 0.0, 1.0)),
            *([Velocity(linear=(6.0, 0.0, 0.0))] if k == CHAIN_LINKS - 1 else []),
        )
    # a character walking a loop around the heap, jumping now and then
    body = add_mesh(cylinder_mesh(radius=0.4, height=1.8))  # type: ignore[operator]
    world.spawn(
        Transform(position=(WALK_LOOP[0][0], 0.9, WALK_LOOP[0][1])),
        Mesh(handle=body, material=looks.add(Material("walker", "cook_torrance", (0.2, 0.5, 0.9, 1.0)))),
        CharacterController(),
    )
    # ragdolls: one standing by the tower to shoot at, one falling onto the ramp
    head, limb = add_mesh(sphere_mesh()), add_mesh(cylinder_mesh())  # type: ignore[operator]
    look = looks.add(Material("ragdoll", "cook_torrance", (0.85, 0.7, 0.55, 1.0)))
    for feet in ((-1.0, 0.0, -8.0), (-14.0, 6.0, -6.0)):
        spawn_ragdoll(world, feet, cube, head, limb, look)
    # a tower to shoot at
    for level in range(10):
        world.spawn(
            Transform(position=(-4.0, 0.5 + level, -8.0)), Mesh(handle=cube, material=crate), RigidBody(), Collider()
        )
    world.spawn(Transform(rotation=look_rotation((-0.4, -1.0, -0.5))), DirectionalLight(illuminance=2.5))
    world.spawn(Transform(position=(0.0, 9.0, 34.0), rotation=look_rotation((0.0, -0.25, -1.0))), Camera(), FlyCamera())


class ShootSystem(System):
    """Shoots a ball from the camera along its view on the `shoot` action (or every half second
    with `autoplay`); keeps the newest BALLS_KEPT balls."""

    def __init__(self, autoplay: bool = False) -> None:
        super().__init__(reads=[Camera, Transform, ActionMap, BallLook], writes=[], name="shoot")
        self.autoplay = autoplay
        self._since = 0.0
        self._fired: list[int] = []

    def run(self, world: World, dt: float) -> None:
        self._since += dt
        if self.autoplay:
            shoot = self._since >= 0.5
        else:
            actions = world.resources.get(ActionMap)
            shoot = actions is not None and actions.action_pressed("shoot")
        if not shoot:
            return
        self._since = 0.0
        cameras = world.query(Transform, with_=(Camera,))
        for batch in cameras:
            eye, rotation = batch[Transform].position[0].copy(), batch[Transform].rotation[0]
            break
        else:
            return
        ahead = -rotation_matrix(rotation)[:3, 2]  # the camera looks along its -z
        look = world.resources[BallLook]
        self._fired.append(
            world.spawn(
                Transform(position=eye + ahead * 1.5),
                Mesh(handle=look.mesh, material=look.material),
                RigidBody(mass=5.0, ccd=True),
                Collider(shape=SPHERE, size=(BALL_RADIUS, BALL_RADIUS, BALL_RADIUS), restitution=0.3),
                Velocity(linear=ahead * BALL_SPEED),
            )
        )
        if len(self._fired) > BALLS_KEPT:
            world.destroy(self._fired.pop(0))


class WalkerSystem(System):
    """Walks each character toward the next corner of WALK_LOOP, jumping every third second."""

    def __init__(self) -> None:
        super().__init__(reads=[Transform, CharacterController], writes=[CharacterController], name="walker")
        self._corner = 1
        self._clock = 0.0

    def run(self, world: World, dt: float) -> None:
        self._clock += dt
        for batch in world.query(Transform, CharacterController):
            walker, where = batch[CharacterController], batch[Transform].position
            goal = np.array(WALK_LOOP[self._corner])
            ahead = goal - where[:, [0, 2]]
            if np.linalg.norm(ahead[0]) < 0.5:
                self._corner = (self._corner + 1) % len(WALK_LOOP)
            direction = ahead / np.maximum(np.linalg.norm(ahead, axis=1)[:, None], 1e-9)
            walker.walk[:, 0], walker.walk[:, 2] = direction[:, 0] * WALK_SPEED, direction[:, 1] * WALK_SPEED
            if self._clock >= 3.0:
                walker.jump[:] = JUMP_SPEED
                self._clock = 0.0
