"""The asteroids HUD: score, health, level and asteroid count in an ImGui window over the game,
and on game over a Restart button (R does the same). Drawn each UI frame by the play loop."""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from ecs_engine.ecs import World

from .asteroids_game import Asteroid, Game, ShipControls

HUD_FLAGS = ("no_decoration", "always_auto_resize", "no_saved_settings", "no_focus_on_appearing", "no_nav")


def draw_hud(imgui: Any, world: World) -> dict[str, tuple[float, float, float, float]]:
    """Build the HUD window; returns the screen rectangles of its widgets (tests click them)."""
    game = world.resources.get(Game)
    rects: dict[str, tuple[float, float, float, float]] = {}
    if game is None:
        return rects
    flags = 0
    for name in HUD_FLAGS:
        flags |= getattr(imgui.WindowFlags_, name).value
    imgui.set_next_window_pos((12.0, 12.0))
    imgui.set_next_window_bg_alpha(0.55)
    if imgui.begin("Asteroids HUD", None, flags)[0]:
        imgui.text(f"score  {game.score:,}")
        imgui.progress_bar(game.health / 100.0, (180.0, 0.0), f"health {game.health:.0f}")
        imgui.text(f"level  {game.level}   asteroids {world.query(Asteroid).count():,}")
        imgui.text(f"shots  {game.shots:,}   hits {game.kills:,}")
        if game.over:
            imgui.text_colored((1.0, 0.35, 0.3, 1.0), "GAME OVER")
            if imgui.button("Restart (R)"):
                world.resources[ShipControls].restart = True
            lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
            rects["restart"] = (lo.x, lo.y, hi.x, hi.y)
    imgui.end()
    return rects


def world_hash(world: World) -> str:
    """A digest of every column of every table (in a fixed order): equal worlds, equal hashes."""
    digest = hashlib.sha256()
    for table in sorted(world.tables, key=lambda t: sorted(c.__name__ for c in t.types)):
        for key in sorted(table.columns, key=lambda k: (k[0].__name__, k[1])):
            digest.update(np.ascontiguousarray(table.columns[key][: table.count]).tobytes())
    return digest.hexdigest()[:16]


def summary(world: World) -> str:
    """The line a run prints at its end (with the world's hash: replays must match it)."""
    game = world.resources[Game]
    state = "game over" if game.over else "playing"
    return (
        f"asteroids: score {game.score} at level {game.level}, health {game.health:.0f} ({state}), "
        f"{game.shots} shots, world {world_hash(world)}"
    )
