"""The user's folders for the engine's own files, as the XDG base directory spec says: the config
folder (the editor's layout, input bindings) and the cache folder (pipeline caches, benchmark
results). A relative XDG_CONFIG_HOME or XDG_CACHE_HOME is ignored, as the spec asks: it would
put the files under whatever folder a command happened to run in."""

from __future__ import annotations

import os
from pathlib import Path


def config_home() -> Path:
    """$XDG_CONFIG_HOME, else ~/.config. RuntimeError when neither gives a folder (no home)."""
    return _base("XDG_CONFIG_HOME", ".config")


def cache_home() -> Path:
    """$XDG_CACHE_HOME, else ~/.cache. RuntimeError when neither gives a folder (no home)."""
    return _base("XDG_CACHE_HOME", ".cache")


def _base(variable: str, fallback: str) -> Path:
    value = os.environ.get(variable, "")
    if os.path.isabs(value):
        return Path(value)
    return Path.home() / fallback  # unset, empty or relative
