"""Entities with Transform and CharacterController as the library's virtual characters (Jolt's
CharacterVirtual): made and removed with the world's structure, moved each fixed step before
the world steps, their position, `grounded` and vertical speed written back. Python per
character: a game has a few."""

from __future__ import annotations

import math
from typing import Any

from ..components import Transform
from ..components.physics import CharacterController

# a character's user_data in the library's buffers: its entity with this bit, so that the body
# table (bodies.py) never takes its row for a rigid body's
CHARACTER_BIT = 1 << 62
STICK = (
    0.0  # m/s: a grounded character moves level (the library keeps it on the ground; downward, it would not step up)
)


class Characters:
    """The characters by entity: the library's Character objects (their vertical speed is kept
    in CharacterController.vertical)."""

    def __init__(self, native: Any) -> None:
        self.native = native
        self.made: dict[int, Any] = {}

    def sync(self, world: Any) -> None:
        """Characters made for new entities with Transform and CharacterController, removed for
        those gone (the library removes one when its object goes)."""
        present: set[int] = set()
        for batch in world.query(Transform, CharacterController, write=()):
            present.update(batch.entities.tolist())
            c, t = batch[CharacterController], batch[Transform]
            for r, e in enumerate(batch.entities.tolist()):
                if e in self.made:
                    continue
                made = self.native.create_character(
                    pos=tuple(t.position[r].tolist()),
                    height=float(c.height[r]),
                    radius=float(c.radius[r]),
                    step_height=float(c.step_height[r]),
                    max_slope=math.degrees(float(c.max_slope[r])),
                )
                made.set_strength(float(c.strength[r]))
                self.native.set_user_data(made.handle, e | CHARACTER_BIT)
                self.made[e] = made
        for e in [e for e in self.made if e not in present]:
            del self.made[e]

    def move(self, world: Any, gravity: float, dt: float) -> None:
        """Each character moved by its walk, jump and gravity (`gravity`: along the world's up)."""
        for batch in world.query(CharacterController):
            c = batch[CharacterController]
            for r, e in enumerate(batch.entities.tolist()):
                made = self.made.get(e)
                if made is None:
                    continue
                grounded, vertical = made.is_grounded(), float(c.vertical[r])
                if grounded and c.jump[r] > 0.0:
                    vertical = float(c.jump[r])
                    c.jump[r] = 0.0
                elif grounded and vertical <= 0.0:
                    vertical = STICK
                else:
                    vertical += gravity * dt
                walk = c.walk[r]
                made.move((float(walk[0]), vertical, float(walk[2])), float(dt))
                c.vertical[r] = vertical

    def write_back(self, world: Any) -> None:
        """Positions into Transform; `grounded` and the vertical speed into CharacterController."""
        for batch in world.query(Transform, CharacterController):
            t, c = batch[Transform], batch[CharacterController]
            for r, e in enumerate(batch.entities.tolist()):
                made = self.made.get(e)
                if made is None:
                    continue
                t.position[r] = made.get_position()
                grounded = made.is_grounded()
                c.grounded[r] = grounded
                if grounded and c.vertical[r] <= 0.0:
                    c.vertical[r] = 0.0
                else:
                    c.vertical[r] = made.get_linear_velocity()[1]
