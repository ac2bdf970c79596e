"""The user's input bindings: `input.json`, or `input-<game>.json` for a game, in the config
folder (editor_dock.config_dir(): XDG_CONFIG_HOME, else ~/.config, then `ecs_engine/`).

A file that cannot be used does not stop the game: the run says, once, what is wrong with it and
plays with the default bindings. A game that refused to start over a typo in its controls file
would be worse than one that starts with controls the player knows and says what to fix. The
file is only read here, never written, so nothing the user wrote is lost; `ActionMap.save` writes
one when asked to.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

from ..systems.action_map import ActionMap, InputConfigError
from .editor_dock import config_dir


def bindings_file(game: str | None = None) -> Path:
    return config_dir() / ("input.json" if game is None else f"input-{game}.json")


def load_bindings(
    defaults: Mapping[str, Iterable[str]],
    game: str | None = None,
    warn: Callable[[str], None] | None = None,
) -> ActionMap:
    """The defaults with the user's file over them; a bad file: a warning and the defaults."""
    path = bindings_file(game)
    try:
        return ActionMap.load(path, defaults)
    except InputConfigError as exc:
        say = warn or (lambda text: print(text, file=sys.stderr))
        say(f"warning: {exc}; playing with the default bindings (the file is left as it is)")
        return ActionMap(defaults)
