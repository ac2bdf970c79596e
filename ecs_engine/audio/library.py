"""The audio library the engine binds: miniaudio (its Python bindings), a dependency of the
engine. Why that one: docs/audio.md."""

from __future__ import annotations

from typing import Any

from ..errors import UsageError


def load() -> Any:
    """The miniaudio module, or UsageError in one line naming what to install."""
    try:
        import miniaudio
    except ImportError:
        raise UsageError("sound needs the miniaudio library: pip install miniaudio") from None
    return miniaudio
