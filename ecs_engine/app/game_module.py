"""Finding and loading a game module: the one place the App loads a game's code from.

A game is a module with `build(app)` (and, if it wants its own command-line options,
`add_arguments(parser)`: what they parse to is `app.options` in build). `ecs-engine play` and
`ecs-engine editor` take one as
- a known name (`asteroids`),
- a file (`path/to/game.py`), or a folder holding `game.py` (what `ecs-engine new` writes),
- a module name (`package.module`), imported as Python imports it.

A file is imported as the module its name makes (`catch.py`: `catch`), with its folder first
on sys.path, as `python catch.py` would see it: the game's other files import as they would
there, and components it defines are saved in scene files as `catch.Star` whichever way it runs
(ecs/scene_file.py names `__main__` the same). Loading the same file again (a reload) replaces
the module; a name another module already has is refused.

Everything that can go wrong with a game's code before it runs (no such file, a syntax error, an
exception on import, no build(app), build failing) is one UsageError naming the file; the
exception it came from is its cause, for --debug.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import inspect
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from ..errors import UsageError
from .app import App

KNOWN_GAMES = {"asteroids": "ecs_engine.demos.asteroids", "physics": "ecs_engine.demos.physics_playground"}
GAME_FILE = "game.py"  # a folder's game (ecs-engine new)

_loaded: dict[str, Path] = {}  # module name -> the file this module loaded it from


@dataclass(frozen=True)
class Game:
    name: str  # the App's name: its first line, its bindings file (input-NAME.json), its PNG
    module: ModuleType
    where: str  # what an error names: the file, or the module

    @property
    def add_arguments(self) -> Callable[[argparse.ArgumentParser], None] | None:
        hook = getattr(self.module, "add_arguments", None)
        return hook if callable(hook) else None


def is_game_spec(text: str) -> bool:
    """Whether a command-line word names a game rather than a demo scene or a scene file."""
    return text in KNOWN_GAMES or text.endswith(".py") or (Path(text) / GAME_FILE).is_file()


def find_game(spec: str) -> Game:
    """The game `spec` names, its module imported (see the module docstring)."""
    if spec in KNOWN_GAMES:
        return _checked(Game(spec, _import(KNOWN_GAMES[spec], spec), spec))
    path = Path(spec)
    if path.is_dir() and (path / GAME_FILE).is_file():
        path = path / GAME_FILE
    if path.suffix == ".py" or path.exists():
        if not path.is_file():
            raise UsageError(f"no game file {spec}" if not path.exists() else f"{spec} is not a Python file")
        module = load_file(path, spec if path.name != GAME_FILE or spec.endswith(".py") else str(path))
        name = path.parent.name if path.name == GAME_FILE else path.stem
        return _checked(Game(name or path.stem, module, str(path)))
    if not all(part.isidentifier() for part in spec.split(".")) or importlib.util.find_spec(spec) is None:
        known = ", ".join(KNOWN_GAMES)
        raise UsageError(f"invalid choice: {spec!r}: not a known game ({known}), a game file (.py) nor a module")
    return _checked(Game(spec.rpartition(".")[2], _import(spec, spec), spec))


def load_file(path: Path, shown: str | None = None) -> ModuleType:
    """Import the game file at `path` as the module its name makes (again if loaded before);
    errors name it as `shown` (default: the path)."""
    shown = shown or str(path)
    path = path.resolve()
    name = path.stem
    if not name.isidentifier():
        raise UsageError(f"{shown}: a game file's name must be a Python module name (letters, digits, _)")
    have = sys.modules.get(name)
    if have is not None and _loaded.get(name) is None:
        where = getattr(have, "__file__", None) or "built in"
        raise UsageError(f"{shown}: its name {name!r} is already a module's ({where}); rename the file")
    folder = str(path.parent)
    if folder not in sys.path:
        sys.path.insert(0, folder)  # its own modules import as they would under `python game.py`
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise UsageError(f"{shown}: cannot be imported as a Python module")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and scene files find its classes by their module
    try:
        spec.loader.exec_module(module)
    except BaseException as exc:
        del sys.modules[name]
        _loaded.pop(name, None)
        if isinstance(exc, Exception):
            raise UsageError(_import_error(shown, exc)) from exc
        raise
    _loaded[name] = path
    return module


def _import(module_name: str, where: str) -> ModuleType:
    try:
        return importlib.import_module(module_name)
    except Exception as exc:
        raise UsageError(_import_error(where, exc)) from exc


def _import_error(where: str, exc: Exception) -> str:
    if isinstance(exc, SyntaxError):
        file = where if exc.filename in (None, "<unknown>") or where.endswith(".py") else exc.filename
        return f"{file}:{exc.lineno}: syntax error: {exc.msg}"
    text = " ".join(str(exc).split())
    return f"{where}: importing it raised {type(exc).__name__}" + (f": {text}" if text else "")


def _checked(game: Game) -> Game:
    build = getattr(game.module, "build", None)
    if not callable(build):
        raise UsageError(f"{game.where}: has no build(app) function (what a game module defines)")
    try:
        signature = inspect.signature(build)
        signature.bind(None)
    except TypeError:
        takes = ", ".join(signature.parameters)
        raise UsageError(f"{game.where}: its build({takes}) is not a game's build(app), which takes the App") from None
    except ValueError:  # a builtin without a signature: let the call say
        pass
    return game


def make_app(game: Game, options: argparse.Namespace | None = None) -> App:
    """A new App named for `game`, its options `options` (the command line's), built by the
    game's build(app)."""
    app = App(name=game.name)
    app.options = options if options is not None else game_defaults(game)
    try:
        game.module.build(app)
    except UsageError:
        raise
    except Exception as exc:
        text = " ".join(str(exc).split())
        raise UsageError(f"{game.where}: build(app) raised {type(exc).__name__}: {text}") from exc
    return app


def game_defaults(game: Game, argv: list[str] | None = None) -> argparse.Namespace:
    """The game's own options (its add_arguments) parsed from `argv` (default: none given)."""
    parser = argparse.ArgumentParser(prog=game.name, add_help=False)
    if game.add_arguments is not None:
        game.add_arguments(parser)
    return parser.parse_args(argv or [])


def game_app(spec: str, argv: list[str] | None = None) -> App:
    """The App of the game `spec` names, its options parsed from `argv` (for tests and scripts)."""
    game = find_game(spec)
    return make_app(game, game_defaults(game, argv))
