"""`ecs-engine play GAME` and `ecs-engine editor GAME`: a game module (game_module.py: a known
name, a .py file, a folder with game.py, or a module name) built into an App and run with the
command line's flags, in a window (or headless), or in the editor.

The game's own options (`add_arguments(parser)`, e.g. asteroids' --level, --seed, --autoplay)
join the command's: the command line is read once to find the game, which is imported, then
again with its options (cli.parse_command).
"""

from __future__ import annotations

import argparse
from typing import Any

from .game_module import KNOWN_GAMES, Game, make_app
from .plugins import EditorPlugin
from .settings import RunOptions

WATCH_HELP = "reload the game's systems, textures and meshes, and the engine's shaders, as their files change"


def add_parser(sub: Any, common: argparse.ArgumentParser, game: Game | None) -> argparse.ArgumentParser:
    play = sub.add_parser(
        "play",
        help=f"play a game: {', '.join(KNOWN_GAMES)}, a game file (game.py), a folder with one, or a module",
        parents=[common],
    )
    play.add_argument(
        "game",
        help=f"a known game ({', '.join(KNOWN_GAMES)}), a file or folder (ecs-engine new NAME writes one), "
        "or a module name; anything with build(app)",
    )
    play.add_argument("--watch", action="store_true", help=WATCH_HELP)
    add_game_arguments(play, game)
    return play


def add_game_arguments(parser: argparse.ArgumentParser, game: Game | None) -> None:
    """The game's own options, as its add_arguments(parser) declares them."""
    if game is not None and game.add_arguments is not None:
        group = parser.add_argument_group(f"{game.name}'s options")
        game.add_arguments(group)  # type: ignore[arg-type]
    # the window's size is the game's unless given (its App(size=...) or WindowPlugin)
    parser.set_defaults(width=None, height=None)


def run_game(
    args: argparse.Namespace, game: Game, editor: bool, headless_frames: int, scenes: tuple[str, ...] = ()
) -> int:
    """Build `game` into an App with `args` as its options, and run it (the flags checked by the
    caller: cli.check_flags_apply)."""
    from .hot_reload import HotReload
    from .scenes import SEED_SCENES

    app = make_app(game, args)
    if editor and not app.has_plugin(EditorPlugin):
        app.add_plugins(EditorPlugin)
    if args.watch:
        HotReload(app, game.module, game.where, debug=args.debug).install()
    width, height = app.size
    switcher = tuple(dict.fromkeys((app.name, *scenes, *SEED_SCENES))) if editor else (app.name,)
    flags = replace_none(args, width=width, height=height)
    options = RunOptions.from_flags(flags, scene=app.name, editor=editor, scenes=switcher)
    options, source = app.prepare(options, headless_frames=headless_frames)
    result = app.launch(options, source)
    return 1 if result.validation_messages else 0


def replace_none(args: argparse.Namespace, **defaults: Any) -> argparse.Namespace:
    """`args` with each of `defaults` where it is None."""
    merged = argparse.Namespace(**vars(args))
    for name, value in defaults.items():
        if getattr(merged, name, None) is None:
            setattr(merged, name, value)
    return merged
