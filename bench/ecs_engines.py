"""The engines the ECS benchmark compares, and a fresh world for each measurement.

esper 3.x is optional (`esper` is None without it, or with esper 2.x, which has no
switch_world), and so is ecs_engine's esper adapter (`adapter_class` says why it is missing).
Every esper or adapter measurement runs in a world of its own so that no run sees another's
entities or query caches; the native engine needs nothing here (each workload makes a World).
"""

from __future__ import annotations

import contextlib
import gc
import itertools
from collections.abc import Iterator
from typing import Any

try:
    import esper
except ImportError:  # pragma: no cover - esper is a dev/bench extra
    esper = None  # type: ignore[assignment]
if esper is not None and not hasattr(esper, "switch_world"):  # pragma: no cover - esper 2.x
    esper = None  # type: ignore[assignment]

_world_names = itertools.count()


@contextlib.contextmanager
def esper_world() -> Iterator[Any]:
    """A fresh esper world context (the module API works on the current one)."""
    assert esper is not None
    name = f"bench-ecs-{next(_world_names)}"
    esper.switch_world(name)
    esper.clear_database()
    try:
        yield esper
    finally:
        esper.clear_database()
        esper.switch_world("default")
        esper.delete_world(name)
        gc.collect()


def adapter_class() -> tuple[Any, str | None]:
    """(EsperWorld, None) if ecs_engine.esper_compat imports, else (None, reason)."""
    try:
        from ecs_engine.esper_compat import EsperWorld  # type: ignore[import-not-found]
    except Exception as exc:
        return None, f"{type(exc).__name__}: {exc}"
    return EsperWorld, None


@contextlib.contextmanager
def adapter_world(cls: Any) -> Iterator[Any]:
    world = cls()
    try:
        yield world
    finally:
        del world
        gc.collect()
