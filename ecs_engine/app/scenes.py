"""The demo scenes by name, and the stock schedule they run with."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from ..ecs.schedule import Schedule
from ..errors import UsageError

SCENES = (
    "cube",
    "grid100",
    "model",
    "scaling",
    "materials",
    "lights",
    "shadows",
    "environment",
    "split_screen",
    "monitor",
    "animation",
)
SEED_SCENES = SCENES[:3]  # the seed thesis's three: 1 cube, 100 cubes, an OBJ model

SceneBuilder = Callable[..., None]  # build(world, add_mesh, path=None)
SCENE_FILE_SUFFIX = ".scene"  # a saved scene (ecs/scene_file.py) opens where a scene name goes


def is_scene_file(name: str) -> bool:
    """Whether `name` is a scene file's path rather than a demo scene's name."""
    return name not in SCENES and name.lower().endswith(SCENE_FILE_SUFFIX)


def scene_builder(name: str, entities: int = 10_000, lights: int | None = None, shadows: bool = True) -> SceneBuilder:
    if name not in SCENES:
        raise UsageError(f"unknown scene {name!r}; scenes: {', '.join(SCENES)}")
    build = importlib.import_module(f"ecs_engine.demos.{name}").build
    if name == "scaling":
        return lambda world, add_mesh, path=None: build(world, add_mesh, path, entities=entities)
    if name == "animation" and entities != 10_000:  # (its own default crowd otherwise)
        return lambda world, add_mesh, path=None: build(world, add_mesh, path, entities=entities)
    if name == "lights" and lights is not None:
        return lambda world, add_mesh, path=None: build(world, add_mesh, path, lights=lights)
    if name == "shadows" and not shadows:
        return lambda world, add_mesh, path=None: build(world, add_mesh, path, shadows=False)
    return build


def scene_systems(name: str) -> list[tuple[str, Any]]:
    """The (stage, system) pairs a demo scene runs besides default_schedule's (its module's
    `systems()`; none for most)."""
    if name not in SCENES:
        return []
    systems = getattr(importlib.import_module(f"ecs_engine.demos.{name}"), "systems", None)
    return [] if systems is None else list(systems())


def default_schedule() -> Schedule:
    """The schedule of the engine's scene plugins (plugins.SCENE_PLUGINS): simulation (snapshot
    for interpolation, orbits, motion, springs) in the fixed-step stage, the fly camera per frame,
    then render origin, matrices and the hierarchy's. `Schedule.run` runs every stage once; the
    run loop uses `Schedule.run_frame` with a FixedTimestep."""
    from . import plugins

    return plugins.schedule_of(plugins.SCENE_PLUGINS)
