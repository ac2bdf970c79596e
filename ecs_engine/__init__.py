"""ecs_engine: entities as NumPy component arrays, systems over whole columns, Vulkan rendering.

Rules of use, in short:
- Components are schemas (`class Health(Component): hp = Field("f4", default=100)`); each field
  is one NumPy column per archetype table.
- `world.spawn(...)`, `world.spawn_batch(n, ...)`, `destroy`, `add`, `remove` change structure;
  inside a system or a query loop they are deferred to the next sync point.
- `world.query(A, B, with_=..., without=..., write=...)` yields per-table batches of column views.
- Values are checked where they enter the world (NaN/Inf, ranges, shapes, dtypes); systems that
  write through views are trusted.
- `world.events(Kind)` is a typed event channel, double-buffered per frame; `Schedule(parallel=
  True)` runs a stage's systems whose declared reads and writes do not conflict at the same time;
  `run_if=any_with(A, B)` skips a system while no entity has A and B.
- Game structure (docs/game-structure.md): `init_state` / `in_state` / `Schedule.on_enter`,
  `world.add_observer(OnAdd(C), f)`, `world.removed(C).read()`, `run_once(world, f)`, `Prefab`.
- `App` runs a game: `App(title=...).add_plugins(DefaultPlugins).add_systems("update", f).run()`
  (docs/app.md); `ecs-engine play game.py` runs a module's `build(app)`.
"""

from typing import TYPE_CHECKING, Any

from .ecs import (
    AccessError,
    Batch,
    Component,
    ComponentView,
    DeadEntityError,
    EcsError,
    Events,
    Field,
    FixedTimestep,
    FunctionSystem,
    MissingComponentError,
    NextState,
    Observer,
    OnAdd,
    OnChange,
    OnRemove,
    Query,
    Removals,
    Schedule,
    State,
    System,
    Trigger,
    World,
    any_with,
    current_state,
    in_state,
    init_state,
    request_state,
    run_once,
    system,
)

if TYPE_CHECKING:
    from .ecs.prefabs import Prefab, spawn_prefab


__version__ = "0.1.0"

# the App and its plugins load the renderer's modules (numba among them): imported on first use,
# so `import ecs_engine` for the ECS alone stays quick
_APP_NAMES = {
    "App": "app",
    "DefaultPlugins": "plugins",
    "MinimalPlugins": "plugins",
    "PluginGroup": "plugins",
    "Plugin": "plugins",
    "Window": "window_resource",
    "Time": "clock",
    "SceneFiles": "scene_saves",
    "BloomPlugin": "post_plugins",
    "FxaaPlugin": "post_plugins",
    "PostEffectPlugin": "post_plugins",
    "SsaoPlugin": "post_plugins",
}


def __getattr__(name: str) -> Any:
    """The App's names and Prefab / spawn_prefab (see ecs/__init__.py): imported when first
    asked for."""
    if name in ("Prefab", "spawn_prefab"):
        from .ecs import prefabs

        return getattr(prefabs, name)
    if name in _APP_NAMES:
        import importlib

        return getattr(importlib.import_module(f".app.{_APP_NAMES[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "AccessError",
    "App",
    "Batch",
    "BloomPlugin",
    "Component",
    "ComponentView",
    "DeadEntityError",
    "DefaultPlugins",
    "EcsError",
    "Events",
    "Field",
    "FixedTimestep",
    "FunctionSystem",
    "FxaaPlugin",
    "MinimalPlugins",
    "MissingComponentError",
    "NextState",
    "Observer",
    "OnAdd",
    "OnChange",
    "OnRemove",
    "Plugin",
    "PluginGroup",
    "PostEffectPlugin",
    "Prefab",
    "Query",
    "Removals",
    "SceneFiles",
    "Schedule",
    "SsaoPlugin",
    "State",
    "System",
    "Time",
    "Trigger",
    "Window",
    "World",
    "any_with",
    "current_state",
    "in_state",
    "init_state",
    "request_state",
    "run_once",
    "spawn_prefab",
    "system",
]
