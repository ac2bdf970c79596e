"""Asteroids, written only as components, resources, events and systems (the scene, meshes and
HUD are in asteroids.py, the bot in asteroids_bot.py).

Play happens on the XZ plane (y = 0), seen from above. The ship turns, thrusts and fires as the
`ShipControls` resource says (filled from the keyboard and mouse, or by the bot); projectiles and
asteroids move with the stock Velocity / AngularVelocity and MotionSystem; everything wraps
around a square arena. A uniform-grid broad phase (ecs_engine.maths.broad_phase) finds which
projectiles hit which asteroids and which asteroids touch the ship; the hits go out as events;
the damage system splits asteroids, scores, hurts the ship; the level system adds asteroids as
the score rises (2,000 at level 1, up to 100,000). Everything random draws from the `Game`
resource's generator, in a fixed order, so a seed and the same controls give the same world.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ecs_engine.components import AngularVelocity, Camera, Mesh, Transform, Velocity
from ecs_engine.ecs import Component, Field, System, World
from ecs_engine.maths.broad_phase import overlapping_pairs
from ecs_engine.maths.camera import look_rotation

LEVEL_ASTEROIDS = (2_000, 5_000, 10_000, 25_000, 50_000, 100_000)
RADII = (0.5, 1.0, 2.0)  # by size class: small, medium, big
POINTS = (100, 50, 20)  # by size class
SHIP_RADIUS = 0.8
DENSITY = 40.0  # arena area (square units) per asteroid of the level's count


class Ship(Component):
    heading = Field(np.float64, default=0.0, finite=True)  # radians about +Y; 0 looks down -Z
    cooldown = Field(np.float64, default=0.0, finite=True)  # seconds until it may fire again
    invulnerable = Field(np.float64, default=0.0, finite=True)  # seconds of grace after a hit


class Asteroid(Component):
    size = Field(np.int8, default=2, minimum=0, maximum=2)  # index into RADII / POINTS


class Projectile(Component):
    life = Field(np.float64, default=1.5, finite=True)  # seconds left


class Collider(Component):
    radius = Field(np.float64, default=1.0, finite=True, minimum=0.0)


class AsteroidHit(Component):
    """An event: projectile `projectile` hit asteroid `asteroid`."""

    asteroid = Field(np.int64, default=-1, entity=True)
    projectile = Field(np.int64, default=-1, entity=True)


@dataclass
class ShipHit:
    """An event: an asteroid of class `size` struck the ship."""

    size: int


@dataclass
class ShipControls:
    """What the ship does this step: turn (-1 right .. 1 left), thrust (-1 .. 1), fire, and
    restart (after game over; a latch the restart system clears). `aim`, when set, is a direction
    (x, z) on the plane the ship turns to face (at its turn rate) instead of `turn`."""

    turn: float = 0.0
    thrust: float = 0.0
    fire: bool = False
    restart: bool = False
    aim: tuple[float, float] | None = None


@dataclass
class Game:
    """The game's state, a resource. `meshes` and `materials` are the handles asteroids.py made."""

    seed: int = 1
    first_level: int = 1  # where a (re)start begins
    score: int = 0
    health: float = 100.0
    level: int = 1
    over: bool = False
    shots: int = 0
    kills: int = 0
    half: float = 0.0  # the arena spans [-half, half) in x and z
    # with physics (asteroids_physics.py): the rigid-body components of asteroids of these radii,
    # or of the ship (ship=True), added where they are spawned; None: the game's own overlap test
    bodies: Callable[..., tuple] | None = None
    meshes: dict[str, int] = field(default_factory=dict)
    materials: dict[str, int] = field(default_factory=dict)
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(1))

    def level_count(self) -> int:
        return LEVEL_ASTEROIDS[min(self.level, len(LEVEL_ASTEROIDS)) - 1]

    def next_level_score(self) -> int:
        return 1_000 * self.level * self.level


def arena_half(count: int) -> float:
    return math.sqrt(count * DENSITY) / 2.0


def heading_rotation(heading: np.ndarray | float) -> np.ndarray:
    """Quaternions (x, y, z, w) of rotations by `heading` about +Y."""
    h = np.asarray(heading, np.float64) * 0.5
    return np.stack([np.zeros_like(h), np.sin(h), np.zeros_like(h), np.cos(h)], axis=-1)


def forward(heading: np.ndarray | float) -> np.ndarray:
    h = np.asarray(heading, np.float64)
    return np.stack([-np.sin(h), np.zeros_like(h), -np.cos(h)], axis=-1)


def spawn_asteroids(
    world: World,
    game: Game,
    n: int,
    sizes: np.ndarray | int,
    at: np.ndarray | None = None,
    velocity: np.ndarray | None = None,
) -> None:
    """n asteroids of the given size classes, at `at` (else anywhere in the arena, away from the
    ship), moving (at `velocity` if given) and spinning at random (drawn from the game's generator)."""
    if n <= 0:
        return
    rng = game.rng
    sizes = np.broadcast_to(np.asarray(sizes, np.int8), (n,)).copy()
    if at is None:
        at = np.zeros((n, 3))
        at[:, [0, 2]] = rng.uniform(-game.half, game.half, (n, 2))
        at[:, [0, 2]] += np.where(np.abs(at[:, [0, 2]]) < 12.0, 24.0, 0.0)  # not on top of the start
    radii = np.asarray(RADII)[sizes]
    drawn = np.zeros((n, 3))
    drawn[:, [0, 2]] = rng.normal(0.0, 2.5, (n, 2)) / np.sqrt(radii)[:, None]  # (drawn anyway: replays' order)
    velocity = drawn if velocity is None else velocity
    world.spawn_batch(
        n,
        Transform(position=at, rotation=rng.normal(size=(n, 4)), scale=np.repeat(2.0 * radii[:, None], 3, 1)),
        Velocity(linear=velocity),
        AngularVelocity(angular=rng.normal(0.0, 1.0, (n, 3))),
        Asteroid(size=sizes),
        Collider(radius=radii),
        Mesh(handle=game.meshes.get("rock", 0), material=game.materials.get("rock", 0)),
        *(game.bodies(radii) if game.bodies is not None else ()),
    )


def start(world: World, game: Game) -> None:
    """A ship at the centre and the first level's asteroids (game.first_level, normally 1)."""
    game.score, game.health, game.over, game.shots, game.kills = 0, 100.0, False, 0, 0
    game.level = min(max(game.first_level, 1), len(LEVEL_ASTEROIDS))
    game.rng = np.random.default_rng(game.seed)
    game.half = arena_half(game.level_count())
    world.spawn(
        Transform(scale=(1.6, 1.6, 1.6)),
        Velocity(),
        Ship(invulnerable=2.0),
        Collider(radius=SHIP_RADIUS),
        Mesh(handle=game.meshes.get("ship", 0), material=game.materials.get("ship", 0)),
        *(game.bodies(np.array([SHIP_RADIUS]), ship=True) if game.bodies is not None else ()),
    )
    spawn_asteroids(world, game, game.level_count(), game.rng.choice(3, game.level_count(), p=(0.2, 0.3, 0.5)))


class ShipSystem(System):
    """Turn, thrust (damped, capped) and fire as the ShipControls say; grace time runs down."""

    TURN, ACCEL, DRAG, TOP, SHOT_SPEED, COOLDOWN = 3.5, 14.0, 0.6, 18.0, 40.0, 0.12

    def __init__(self) -> None:
        super().__init__(reads=[ShipControls], writes=[Game, Ship, Transform, Velocity], name="ship")

    def run(self, world: World, dt: float) -> None:
        controls, game = world.resources[ShipControls], world.resources[Game]
        if game.over:
            return
        for batch in world.query(Ship, Transform, Velocity):
            ship, t, v = batch[Ship], batch[Transform], batch[Velocity]
            ship.heading += self.turn_step(controls, ship.heading, dt)
            t.rotation = heading_rotation(ship.heading)
            ahead = forward(ship.heading)
            v.linear += ahead * (np.clip(controls.thrust, -1.0, 1.0) * self.ACCEL * dt)
            v.linear *= math.exp(-self.DRAG * dt)
            speed = np.linalg.norm(v.linear, axis=1, keepdims=True)
            v.linear *= np.minimum(1.0, self.TOP / np.maximum(speed, 1e-9))
            ship.cooldown = np.maximum(ship.cooldown - dt, 0.0)
            ship.invulnerable = np.maximum(ship.invulnerable - dt, 0.0)
            ready = (ship.cooldown <= 0.0) & bool(controls.fire)
            for row in np.flatnonzero(ready):
                ship.cooldown[row] = self.COOLDOWN
                game.shots += 1
                world.spawn(
                    Transform(position=t.position[row] + ahead[row] * 1.2, scale=(0.25, 0.25, 0.25)),
                    Velocity(linear=v.linear[row] + ahead[row] * self.SHOT_SPEED),
                    Projectile(),
                    Collider(radius=0.25),
                    Mesh(handle=game.meshes.get("shot", 0), material=game.materials.get("shot", 0)),
                )

    @classmethod
    def turn_step(cls, controls: ShipControls, heading: np.ndarray, dt: float) -> np.ndarray | float:
        """This step's turn: toward `aim` (stopping on it), else as `turn` says."""
        if controls.aim is None:
            return np.clip(controls.turn, -1.0, 1.0) * cls.TURN * dt  # (this order: replays' hashes)
        most = cls.TURN * dt
        wanted = math.atan2(-controls.aim[0], -controls.aim[1])  # heading 0 looks down -Z
        error = np.mod(wanted - heading + math.pi, 2.0 * math.pi) - math.pi
        return np.clip(error, -most, most)


class WrapSystem(System):
    """Whatever leaves the arena comes back on the other side."""

    def __init__(self) -> None:
        super().__init__(reads=[Game, Collider], writes=[Transform], name="wrap")

    def run(self, world: World, dt: float) -> None:
        half = world.resources[Game].half
        for batch in world.query(Transform, with_=(Collider,)):
            p = batch[Transform].position
            for axis in (0, 2):  # in place on the column views: no copies of 100,000 rows
                x = p[:, axis]
                outside = np.flatnonzero((x < -half) | (x >= half))
                if len(outside):
                    x[outside] = np.mod(x[outside] + half, 2.0 * half) - half


class LifetimeSystem(System):
    """Projectiles expire."""

    def __init__(self) -> None:
        super().__init__(writes=[Projectile], name="lifetime")

    def run(self, world: World, dt: float) -> None:
        for batch in world.query(Projectile):
            life = batch[Projectile].life
            life -= dt
            expired = batch.entities[life <= 0.0]
            if len(expired):
                world.destroy(expired)


def _gather(world: World, kind: type) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ids, positions, radii = [], [], []
    for batch in world.query(Transform, Collider, with_=(kind,), write=()):
        ids.append(batch.entities)
        positions.append(batch[Transform].position)
        radii.append(batch[Collider].radius)
    if not ids:
        return np.empty(0, np.int64), np.empty((0, 3)), np.empty(0)
    return np.concatenate(ids), np.concatenate(positions), np.concatenate(radii)


class CollisionSystem(System):
    """The broad phase each step: projectile-asteroid hits (each projectile and each asteroid
    counted once, nearest pair order) and asteroid-ship contacts, sent as events."""

    def __init__(self) -> None:
        super().__init__(
            reads=[Transform, Collider, Projectile, Asteroid, Ship, Game], writes=[AsteroidHit, ShipHit], name="collide"
        )

    def run(self, world: World, dt: float) -> None:
        rocks, rock_at, rock_r = _gather(world, Asteroid)
        if not len(rocks):
            return
        shots, shot_at, shot_r = _gather(world, Projectile)
        if len(shots):
            i_shot, i_rock = overlapping_pairs(shot_at, shot_r, rock_at, rock_r)
            _, first = np.unique(i_shot, return_index=True)  # one asteroid per projectile
            i_shot, i_rock = i_shot[first], i_rock[first]
            _, first = np.unique(i_rock, return_index=True)  # one projectile per asteroid
            if len(first):
                hit = AsteroidHit(asteroid=rocks[i_rock[first]], projectile=shots[i_shot[first]])
                world.events(AsteroidHit).send(hit)
        ships, ship_at, ship_r = _gather(world, Ship)
        game = world.resources[Game]
        if len(ships) and not game.over and game.bodies is None:  # (with physics: its contacts, asteroids_physics.py)
            _, i_rock = overlapping_pairs(ship_at, ship_r, rock_at, rock_r)
            if len(i_rock):  # one contact a step: the first asteroid's size class
                world.events(ShipHit).send(ShipHit(int(world.get(int(rocks[i_rock[0]]), Asteroid).size)))


class DamageSystem(System):
    """Hit asteroids break into two of the next size down (the smallest vanish), score by size;
    a contact costs the ship health unless it is in its grace time; none left: game over."""

    def __init__(self) -> None:
        super().__init__(
            reads=[AsteroidHit, ShipHit, Transform, Velocity],
            writes=[Game, Asteroid, Ship],
            name="damage",
        )

    def run(self, world: World, dt: float) -> None:
        game = world.resources[Game]
        hits = world.events(AsteroidHit).read()
        if len(hits):
            rocks = hits.asteroid
            sizes = np.array([int(world.get(int(e), Asteroid).size) for e in rocks], np.int8)
            at = np.array([world.get(int(e), Transform).position for e in rocks])
            game.score += int(np.asarray(POINTS)[sizes].sum())
            game.kills += len(rocks)
            world.destroy(np.concatenate([rocks, hits.projectile]))
            split = sizes > 0
            if split.any():
                pieces = np.repeat(at[split], 2, axis=0)
                spawn_asteroids(world, game, len(pieces), np.repeat(sizes[split] - 1, 2), at=pieces)
        for hit in world.events(ShipHit).read():
            for batch in world.query(Ship):
                ship = batch[Ship]
                if game.over or ship.invulnerable[0] > 0.0:
                    continue
                game.health = max(game.health - 10.0 * (hit.size + 1), 0.0)
                ship.invulnerable[:] = 1.5
                if game.health <= 0.0:
                    game.over = True


class LevelSystem(System):
    """The next level when the score reaches 1,000 x level^2: a larger arena, more asteroids."""

    def __init__(self) -> None:
        super().__init__(reads=[Asteroid], writes=[Game], name="level")

    def run(self, world: World, dt: float) -> None:
        game = world.resources[Game]
        if game.over or game.score < game.next_level_score() or game.level >= len(LEVEL_ASTEROIDS):
            return
        game.level += 1
        game.half = max(game.half, arena_half(game.level_count()))
        missing = game.level_count() - world.query(Asteroid).count()
        spawn_asteroids(world, game, missing, game.rng.choice(3, max(missing, 0), p=(0.2, 0.3, 0.5)))


class RestartSystem(System):
    """After game over, the restart control clears the field and starts level 1 again."""

    def __init__(self) -> None:
        super().__init__(writes=[ShipControls, Game, Asteroid, Projectile, Ship], name="restart")
        self.exclusive = True  # it destroys and spawns everything

    def run(self, world: World, dt: float) -> None:
        game, controls = world.resources[Game], world.resources[ShipControls]
        wanted, controls.restart = controls.restart, False  # consumed (a press while playing is dropped)
        if not (game.over and wanted):
            return
        for kind in (Asteroid, Projectile, Ship):
            ids = world.query(kind).entities()
            if len(ids):
                world.destroy(ids)
        start(world, game)


class FollowCameraSystem(System):
    """The camera hangs above and behind the ship, looking at it."""

    OFFSET = np.array([0.0, 34.0, 14.0])

    def __init__(self) -> None:
        super().__init__(reads=[Ship, Camera], writes=[Transform], name="follow_camera")

    def run(self, world: World, dt: float) -> None:
        ships = [b[Transform].position[0].copy() for b in world.query(Transform, with_=(Ship,)) if len(b)]
        if not ships:
            return
        eye = ships[0] + self.OFFSET
        for batch in world.query(Transform, with_=(Camera,)):
            batch[Transform].position = eye
            batch[Transform].rotation = look_rotation(-self.OFFSET)
