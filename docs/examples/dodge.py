"""Dodge: rocks fall, you slide left and right under them. Each rock that reaches the ground
scores its points; each one that hits you costs a life (you blink red and cannot be hit for a
second). A menu, pause, game over and restart, as a state machine:

    MENU --start--> PLAYING --pause--> PAUSED --pause--> PLAYING --last life--> GAME_OVER
    PAUSED or GAME_OVER --restart--> PLAYING (a new game), GAME_OVER --start--> PLAYING

Keys: left / right or A / D (or the left stick) move, Space or Enter (gamepad A) start,
P (gamepad Start) pauses, R (gamepad Y) restarts, Esc quits.

    ecs-engine play docs/examples/dodge.py
    ecs-engine play docs/examples/dodge.py --lives 5 --seed 7
    ecs-engine play docs/examples/dodge.py --headless --frames 300 --screenshot dodge.png --input-script keys.txt
    ecs-engine editor docs/examples/dodge.py

A run prints one line at its end: the state it ended in, the path of states it went through,
the score, the lives, the rocks falling, where the player is and a hash of the world (the same
input script gives the same hash).
"""

from __future__ import annotations

import argparse
import hashlib
import math
from dataclasses import dataclass, field
from enum import Enum, auto

import numpy as np

from ecs_engine import (
    App,
    Component,
    DefaultPlugins,
    Field,
    OnAdd,
    OnRemove,
    Window,
    current_state,
    in_state,
    request_state,
    run_once,
    system,
)
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform
from ecs_engine.maths.broad_phase import overlapping_pairs
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render import Material, Meshes, cube_mesh, materials, plane_mesh, sphere_mesh
from ecs_engine.systems import ActionMap

ACTIONS = {
    "move": ["left/right", "a/d", "gamepad_left_x"],
    "start": ["space", "enter", "gamepad_a"],
    "pause": ["p", "gamepad_start"],
    "restart": ["r", "gamepad_y"],
}
HALF_WIDTH = 8.0  # the player and the rocks stay in x in [-HALF_WIDTH, HALF_WIDTH]
ROCKS = 12  # falling at once
PLAYER_RADIUS, ROCK_RADIUS = 0.6, 0.5
STUN_SECONDS = 1.0


class Play(Enum):
    MENU = auto()
    PLAYING = auto()
    PAUSED = auto()
    GAME_OVER = auto()


class Player(Component):
    speed = Field(np.float64, default=10.0, finite=True, minimum=0.0)


class Rock(Component):
    fall = Field(np.float64, default=6.0, finite=True)  # units per second, downwards
    points = Field(np.int32, default=10)


class Stunned(Component):
    """On the player after a hit: it cannot be hit again until `left` runs out."""

    left = Field(np.float64, default=STUN_SECONDS, finite=True)


@dataclass
class Game:
    """The game's state that is not per entity; `path` is every state entered, in order."""

    lives: int = 3
    start_lives: int = 3
    score: int = 0
    dodged: int = 0
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(1))
    path: list[str] = field(default_factory=list)


@dataclass
class Art:
    """The meshes and materials that `setup` makes, for rocks spawned later."""

    rock_mesh: int = -1
    rock_material: int = -1
    player_material: int = -1
    hurt_material: int = -1


def drop_rocks(world, n, low=10.0, high=22.0):
    """`n` new rocks at random places above the screen."""
    game, art = world.resources[Game], world.resources[Art]
    x, y = game.rng.uniform(-HALF_WIDTH, HALF_WIDTH, n), game.rng.uniform(low, high, n)
    world.spawn_batch(
        n,
        Transform(position=np.c_[x, y, np.zeros(n)]),
        Rock(fall=game.rng.uniform(4.0, 8.0, n), points=game.rng.integers(1, 4, n) * 10),
        Mesh(handle=art.rock_mesh, material=art.rock_material),
    )


def setup(world, dt):
    """Once, before the first frame: meshes, materials, the player, the ground, a light, the camera."""
    meshes, looks, art = world.resources[Meshes], materials(world), world.resources[Art]
    art.rock_mesh = meshes.add(sphere_mesh(16, 8, radius=ROCK_RADIUS))
    art.rock_material = looks.add(Material("rock", base_color=(0.55, 0.45, 0.4, 1.0), roughness=0.9))
    art.player_material = looks.add(Material("player", base_color=(0.2, 0.6, 1.0, 1.0), roughness=0.3))
    art.hurt_material = looks.add(Material("hurt", base_color=(1.0, 0.15, 0.1, 1.0), emissive=(0.6, 0.05, 0.0)))
    ground = looks.add(Material("ground", base_color=(0.25, 0.5, 0.25, 1.0), roughness=1.0))
    world.spawn(
        Transform(scale=(1.2, 1.2, 1.2)), Mesh(handle=meshes.add(cube_mesh()), material=art.player_material), Player()
    )
    world.spawn(
        Transform(position=(0.0, -0.6, 0.0), scale=(2 * HALF_WIDTH + 4, 1.0, 6.0)),
        Mesh(handle=meshes.add(plane_mesh()), material=ground),
    )
    world.spawn(Transform(rotation=look_rotation((-0.3, -1.0, -0.5))), DirectionalLight(illuminance=2.5))
    eye = np.array([0.0, 7.0, 20.0])
    world.spawn(Transform(position=eye, rotation=look_rotation((0.0, -3.0, -20.0))), Camera(fov_y=math.radians(50)))
    drop_rocks(world, ROCKS)


# The state machine: keys move it between states; on-enter and on-exit systems do the rest.


def start(world, dt):
    """MENU and GAME_OVER: the "start" action begins a game (leaving GAME_OVER resets it)."""
    if world.resources[ActionMap].action_pressed("start"):
        request_state(world, Play.PLAYING)


def pause(world, dt):
    """PLAYING <-> PAUSED on the "pause" action."""
    if world.resources[ActionMap].action_pressed("pause"):
        now = current_state(world, Play)
        request_state(world, Play.PAUSED if now is Play.PLAYING else Play.PLAYING)


def restart(world, dt):
    """PAUSED and GAME_OVER: the "restart" action begins a new game at once."""
    if world.resources[ActionMap].action_pressed("restart"):
        if current_state(world, Play) is Play.PAUSED:
            run_once(world, new_game)  # GAME_OVER's on-exit does it otherwise
        request_state(world, Play.PLAYING)


def new_game(world, dt):
    """Lives and score back, the player in the middle and unhurt, every rock gone (refill
    brings new ones: it sees them removed)."""
    game, art = world.resources[Game], world.resources[Art]
    game.lives, game.score, game.dodged = game.start_lives, 0, 0
    for batch in world.query(Transform, Mesh, with_=[Player], write=[Transform, Mesh]):
        batch[Transform].position[:, 0] = 0.0
        batch[Mesh].material[:] = art.player_material
    world.remove(world.query(Stunned).entities(), Stunned)
    world.destroy(world.query(Rock).entities())


def entered(world, dt):
    """Every on-enter: the path of states for the summary, and the window's title."""
    now = current_state(world, Play)
    world.resources[Game].path.append(now.name)
    world.resources[Window].title = f"Dodge: {now.name.lower().replace('_', ' ')}"


# Playing: these run only in PLAYING, in the fixed step (the same steps for the same input).


@system(reads=[Player, ActionMap], writes=[Transform])
def steer(world, dt):
    push = world.resources[ActionMap].axis("move")
    for batch in world.query(Transform, Player):
        x = batch[Transform].position[:, 0]
        x[:] = np.clip(x + batch[Player].speed * push * dt, -HALF_WIDTH, HALF_WIDTH)


@system(reads=[Rock], writes=[Transform, Game])
def fall(world, dt):
    """Rocks fall; one that reaches the ground is dodged and scores."""
    game = world.resources[Game]
    for batch in world.query(Transform, Rock):
        y = batch[Transform].position[:, 1]
        y -= batch[Rock].fall * dt
        landed = y < -0.5
        game.score += int(batch[Rock].points[landed].sum())
        game.dodged += int(landed.sum())
        world.destroy(batch.entities[landed])


@system(reads=[Transform, Player, Rock], writes=[Stunned])
def collide(world, dt):
    """A rock that touches an unhurt player is gone, and the player is stunned."""
    players = world.query(Transform, with_=[Player], without=[Stunned])
    rocks = world.query(Transform, with_=[Rock])
    who, hit = overlapping_pairs(
        players.column(Transform.position), PLAYER_RADIUS, rocks.column(Transform.position), ROCK_RADIUS
    )
    if len(hit):
        world.destroy(np.unique(rocks.entities()[hit]))
        world.add(np.unique(players.entities()[who]), Stunned())


@system(writes=[Stunned])
def recover(world, dt):
    for batch in world.query(Stunned):
        left = batch[Stunned].left
        left -= dt
        world.remove(batch.entities[left <= 0.0], Stunned)


@system(reads=[Rock], writes=[Game])
def refill(world, dt):
    """Removal detection: every rock removed (landed, hit, or cleared by a new game) is replaced."""
    gone = world.removed(Rock).read()
    if len(gone):
        drop_rocks(world, len(gone))


# Observers: whatever adds or removes Stunned (a hit, recovery, a new game), the player's look
# and lives follow.


def hurt(world, trigger):
    game = world.resources[Game]
    game.lives = max(0, game.lives - len(trigger.entities))
    world.set(trigger.entities, Mesh, material=world.resources[Art].hurt_material)
    if game.lives == 0:
        request_state(world, Play.GAME_OVER)


def healed(world, trigger):
    world.set(trigger.entities, Mesh, material=world.resources[Art].player_material)


def hud(imgui, world):
    """The menu, the score and lives, pause and game over, over the game."""
    game, now = world.resources[Game], current_state(world, Play)
    imgui.set_next_window_pos((12.0, 12.0))
    imgui.begin("Dodge", None, imgui.WindowFlags_.always_auto_resize.value)
    if now is Play.MENU:
        imgui.text("DODGE: rocks fall, slide under them")
        imgui.text("Space / Enter / gamepad A: start")
    else:
        imgui.text(f"score {game.score}   lives {game.lives}   dodged {game.dodged}")
    if now is Play.PAUSED:
        imgui.text("paused: P to go on, R to restart")
    if now is Play.GAME_OVER:
        imgui.text("GAME OVER: Space to play again")
    imgui.end()


def world_hash(world):
    """A hash of what the game is: the player's and every rock's place, score and lives."""
    digest = hashlib.sha256()
    for kind in (Player, Rock):
        query = world.query(Transform, with_=[kind])
        digest.update(query.entities().tobytes())
        digest.update(np.ascontiguousarray(query.column(Transform.position)).tobytes())
    game = world.resources[Game]
    digest.update(f"{game.score} {game.lives} {game.dodged}".encode())
    return digest.hexdigest()[:16]


def summary(world):
    game = world.resources[Game]
    state = current_state(world, Play).name
    path = ">".join(game.path)
    rocks = world.query(Rock).count()
    x = float(world.query(Transform, with_=[Player]).column(Transform.position)[0, 0])
    hashed = world_hash(world)
    return f"dodge: {state} path {path} score {game.score} lives {game.lives} rocks {rocks} x {x:.2f} world {hashed}"


def lives(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a whole number from 1 to 9, not {text!r}") from None
    if not 1 <= value <= 9:
        raise argparse.ArgumentTypeError(f"a whole number from 1 to 9, not {value}")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--lives", type=lives, default=3, help="lives at the start of a game (1 to 9, default 3)")
    parser.add_argument("--seed", type=int, default=1, help="where the rocks fall (default 1)")


def build(app: App) -> None:
    start_lives, seed = getattr(app.options, "lives", 3), getattr(app.options, "seed", 1)
    app.title = "Dodge"
    app.add_plugins(DefaultPlugins)
    app.add_actions(ACTIONS)
    app.insert_resource(Game(lives=start_lives, start_lives=start_lives, rng=np.random.default_rng(seed)))
    app.insert_resource(Art())
    app.add_startup_systems(setup)
    app.init_state(Play.MENU)
    app.add_systems("update", start, run_if=lambda world: current_state(world, Play) in (Play.MENU, Play.GAME_OVER))
    app.add_systems("update", pause, run_if=lambda world: current_state(world, Play) in (Play.PLAYING, Play.PAUSED))
    app.add_systems("update", restart, run_if=lambda world: current_state(world, Play) in (Play.PAUSED, Play.GAME_OVER))
    app.add_systems("fixed", steer, fall, collide, recover, run_if=in_state(Play.PLAYING))
    app.add_systems("update", refill)  # in every state: a removal unread for two frames is lost
    for state in Play:  # one system per state: every system of an App has a name of its own
        app.on_enter(state, system(name=f"enter_{state.name.lower()}")(entered))
    app.on_exit(Play.GAME_OVER, new_game)
    app.add_observer(OnAdd(Stunned), hurt)
    app.add_observer(OnRemove(Stunned), healed)
    app.add_ui(hud)
    app.set_summary(summary)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Dodge")
    add_arguments(parser)
    app = App(size=(1280, 720))
    app.options = parser.parse_args()
    build(app)
    app.run()
