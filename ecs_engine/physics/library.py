"""The physics library the engine binds: culverin (Jolt Physics), an optional extra. Why that
one: docs/physics.md."""

from __future__ import annotations

import sys
from typing import Any

from ..errors import UsageError

EXTRA = "pip install 'ecs_engine[physics]'"


def load() -> Any:
    """The culverin module, or UsageError in one line naming the extra to install (and, before
    CPython 3.12, that it has no wheels there)."""
    try:
        import culverin
    except ImportError:
        if sys.version_info < (3, 12):
            here = ".".join(map(str, sys.version_info[:2]))
            raise UsageError(
                f"physics needs culverin (Jolt Physics), which has wheels for CPython 3.12 and newer; "
                f"this is {here}: use Python 3.12+ (make clean; PYTHON=python3.12 make ...) and {EXTRA}"
            ) from None
        raise UsageError(f"physics needs the optional library culverin (Jolt Physics): {EXTRA}") from None
    return culverin
