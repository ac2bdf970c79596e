"""`ecs-engine play GAME`: a game from demos/ in a window (or headless), with its HUD.

A game module provides `build(world, add_mesh, path, seed=, autoplay=, level=)`, `LEVELS`
(how many levels there are: --level goes from 1 to it), `ACTIONS` (its actions' default
bindings), `controls()` (the system turning actions into the game's controls),
`schedule(autoplay, controls)` (its systems), `draw_hud(imgui, world)` and `summary(world)` (the
line printed at the end, before the run's files are written). The run is the engine's one loop (loop.py) with a
`GameSession` (the game's world and schedule instead of a demo scene's) and a `GameUI` (the HUD
on the ImGui session). Keys, mouse and gamepads reach the game through the InputState resource
and the ActionMap resource (the game's ACTIONS with the user's `input-<game>.json` over them,
bindings.py), which ignores the mouse while the HUD has it and keys while it has the keyboard.
"""

from __future__ import annotations

import argparse
import importlib
from dataclasses import replace
from typing import Any

from ..ecs.schedule import Schedule
from ..ecs.world import World
from ..errors import UsageError
from ..jobs import JobPool
from ..systems.action_map import ActionMap
from .bindings import load_bindings
from .imgui_session import ImGuiSession
from .perf import PerfMonitor
from .session import FrameSource, Session
from .settings import RunOptions

GAMES = {"asteroids": "ecs_engine.demos.asteroids"}


def game_module(name: str) -> Any:
    if name not in GAMES:
        raise UsageError(f"unknown game {name!r}; games: {', '.join(GAMES)}")
    return importlib.import_module(GAMES[name])


class GameSession(Session):
    """A session whose world and schedule are the game's."""

    def __init__(self, options: RunOptions, source: FrameSource, game: str, seed: int, autoplay: bool, level: int):
        self.game, self.module = game, game_module(game)
        self.seed, self.autoplay, self.level = seed, autoplay, level
        super().__init__(options, source)
        self.scene = game  # what the run's first line names

    def _build(self, scene: str, path: str | None) -> tuple[World, Schedule]:
        world = World()
        world.resources[JobPool] = self.pool
        if not self.autoplay:  # the bot needs no bindings (build puts the defaults there)
            world.resources[ActionMap] = load_bindings(self.module.ACTIONS, self.game)
        self.module.build(world, self.gpu.meshes.add, seed=self.seed, autoplay=self.autoplay, level=self.level)
        controls = None if self.autoplay else self.module.controls()
        return world, self.module.schedule(autoplay=self.autoplay, controls=controls)


class GameUI(ImGuiSession):
    """The game's HUD on the run's ImGui session."""

    def __init__(self, session: GameSession, window: Any = None) -> None:
        super().__init__(session, window, max_ui_hz=None)
        self.module = session.module
        self.rects: dict[str, tuple[float, float, float, float]] = {}

    def draw(self, world: World, stats: Any, perf: PerfMonitor) -> None:
        self.rects = self.module.draw_hud(self.imgui, world)


def add_parser(sub: Any, common: argparse.ArgumentParser, positive_int: Any, non_negative_int: Any) -> None:
    play = sub.add_parser("play", help="play a game written as systems (asteroids)", parents=[common])
    play.add_argument("game", choices=tuple(GAMES), help="the game")
    play.add_argument("--autoplay", action="store_true", help="a bot plays (reproducible with --seed)")
    play.add_argument("--seed", type=non_negative_int, default=1, help="the game's random seed, 0 or more (default 1)")
    play.add_argument(
        "--level", type=positive_int, default=1, help="the level to start at (asteroids: 1 to 6, 6: 100,000 asteroids)"
    )


def run_play(args: argparse.Namespace, fallback_frames: int, headless_frames: int) -> int:
    """`fallback_frames`: a run that wanted a window and found no display; `headless_frames`:
    a --headless run without --frames."""
    from .loop import run
    from .report import report_validation

    module = game_module(args.game)
    if args.level > module.LEVELS:
        raise UsageError(f"--level {args.level}: {args.game} has levels 1 to {module.LEVELS}")
    holder: list[GameSession] = []

    def make(options: RunOptions, source: FrameSource) -> Session:
        holder.append(GameSession(options, source, args.game, args.seed, args.autoplay, args.level))
        return holder[-1]

    def ui(session: Session, window: Any) -> ImGuiSession:
        assert isinstance(session, GameSession)
        return GameUI(session, window)

    options = RunOptions.from_flags(args, scene="cube")  # the scene is unused: the game builds the world
    source = None
    if not args.headless:
        from .output_files import check_run_files
        from .window import WindowSource, open_glfw

        check_run_files(options)  # before a window opens
        glfw = open_glfw()
        if glfw is not None:
            source = WindowSource(glfw)
        else:
            options = replace(options, headless=True, frames=args.frames or fallback_frames)
            print(f"no display found: playing {options.frames} frames headless instead")
    elif options.frames is None:
        options = replace(options, frames=headless_frames)
    # the score and world hash are said before the files are written: a failed write keeps them
    result = run(options, source, make_session=make, ui=ui, summary=lambda session: module.summary(session.world))
    return report_validation(result)
