"""Plugins: what an App is made of. A plugin is a function `plugin(app)` or a class with
`build(app)` (passed as the class, or as an instance carrying settings); it adds resources,
systems, startup systems, UI and hooks to the App the way a game does.

The engine's own parts are plugins, and two groups bundle them:

- `DefaultPlugins`: time and the fixed step, input, a window, rendering, motion, the fly camera,
  transforms and the hierarchy, picking, scene files and the perf lines: a game in a window.
- `MinimalPlugins`: time, motion, transforms and the hierarchy: a pure simulation, no window
  and no GPU (Vulkan is not even loaded), that `app.run(frames=N)` steps.

A group may leave one out or swap one for another instance:

    app.add_plugins(DefaultPlugins.without(PerfPlugin))
    app.add_plugins(DefaultPlugins.set(WindowPlugin(fullscreen=True)))

The stock schedule the demo scenes run (scenes.default_schedule) is `SCENE_PLUGINS`' systems.
A plugin adds nothing to a frame but its systems: its resources are made once, when the run opens.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

from ..ecs.schedule import Schedule, System
from ..errors import UsageError

STAGES = ("fixed", "update", "post_update")  # an App's stages: what the run loop's frame runs, in order

# what a plugin builds into: app.py's App (not imported here: the App imports its plugins); and
# the Session it hooks with on_open (session.py)
App = Any
Session = Any


class Plugin:
    """A base for plugin classes (any class with `build(app)` will do)."""

    def build(self, app: App) -> None:
        raise NotImplementedError

    def __repr__(self) -> str:
        return type(self).__name__


class TimePlugin(Plugin):
    """The fixed step: the interpolation snapshot at the head of the "fixed" stage, and the
    `Time` resource (app/clock.py)."""

    def build(self, app: App) -> None:
        from ..systems import SnapshotSystem
        from .clock import Time

        app.add_systems("fixed", SnapshotSystem())  # first: what each step starts from

        def clock(world: Any, session: Session) -> None:
            world.resources[Time] = Time(session.source.clock)

        app.on_open(clock)


class MotionPlugin(Plugin):
    """Velocity and AngularVelocity, Orbit and Spring move entities, in the fixed step."""

    def build(self, app: App) -> None:
        from ..systems import MotionSystem, OrbitSystem, SpringSystem

        app.add_systems("fixed", OrbitSystem(), MotionSystem(), SpringSystem())


class AnimationPlugin(Plugin):
    """AnimationPlayer components play the AnimationClips resource's clips on their targets,
    each frame before the transforms (ecs_engine/animation/player.py); AnimationLayers blend more
    clips over them (animation/layers.py)."""

    def build(self, app: App) -> None:
        from ..animation import AnimationClips
        from ..animation.layers import AnimationLayerSystem, AnimationMasks
        from ..animation.player import AnimationSystem

        app.world.resources.setdefault(AnimationClips, AnimationClips())
        app.world.resources.setdefault(AnimationMasks, AnimationMasks())
        app.add_systems("update", AnimationSystem(), AnimationLayerSystem())


class CameraControlPlugin(Plugin):
    """A camera with FlyCamera flies on the keys and mouse (systems/camera_control.py)."""

    def build(self, app: App) -> None:
        from ..systems import FlyCameraSystem

        app.add_systems("update", FlyCameraSystem())


class TransformPlugin(Plugin):
    """The render origin and every Transform's model matrix, in "post_update"."""

    def build(self, app: App) -> None:
        from ..systems import RenderOriginSystem, TransformSystem

        app.add_systems("post_update", RenderOriginSystem(), TransformSystem())


class HierarchyPlugin(Plugin):
    """Children's matrices from their Parent's, after TransformPlugin's; then the skins' joint
    matrices from their joints' (animation/skins.py)."""

    def build(self, app: App) -> None:
        from ..animation.skins import SkinSystem
        from ..systems import HierarchySystem

        app.add_systems("post_update", HierarchySystem(), SkinSystem())


class InputPlugin(Plugin):
    """The InputState resource (keys, mouse, gamepads: a window fills it, an input script too).
    A game's actions come with `app.add_actions(...)` (the ActionMap resource)."""

    def build(self, app: App) -> None:
        from ..systems import InputState

        app.world.resources.setdefault(InputState, InputState())


class WindowPlugin(Plugin):
    """A window when there is a display (headless when asked, or none: a PNG of the last frame
    instead). Its settings start the `Window` resource, which the game may change later."""

    def __init__(
        self,
        title: str | None = None,
        size: tuple[int, int] | None = None,
        fullscreen: bool = False,
        cursor_captured: bool = False,
    ) -> None:
        self.title, self.size = title, size
        self.fullscreen, self.cursor_captured = fullscreen, cursor_captured

    def build(self, app: App) -> None:
        app.windowed = True
        if self.title is not None:
            app.title = self.title
        if self.size is not None:
            app.size = self.size
        app.window.fullscreen, app.window.cursor_captured = self.fullscreen, self.cursor_captured


class RenderPlugin(Plugin):
    """The GPU: a device, the window's swapchain or an offscreen image, and the renderer that
    draws every entity with Transform and Mesh (lights, camera, materials and environment are
    components and resources: README's Rendering)."""

    def build(self, app: App) -> None:
        app.renders = True


class PickingPlugin(Plugin):
    """The `Picker` resource: the entity drawn under a point of the view (app/picker.py)."""

    def build(self, app: App) -> None:
        from .picker import Picker

        def picker(world: Any, session: Session) -> None:
            if app.renders:
                world.resources[Picker] = Picker(session.gpu.meshes)

        app.on_open(picker)


class ScenePlugin(Plugin):
    """Scene files: `world.save(path)` keeps meshes, materials, textures and the environment by
    reference, and `world.resources[SceneFiles].save(path)` does it from a system (at the end of
    the frame); `load`: a scene file added to the world before the startup systems run."""

    def __init__(self, load: str | None = None) -> None:
        self.load = load

    def build(self, app: App) -> None:
        from ..render.assets import scene_assets  # noqa: F401 - registers the scene codecs
        from .scene_saves import SceneFiles

        app.scene_files = SceneFiles(app.world)
        app.insert_resource(app.scene_files)
        path = self.load
        if path is not None:

            def load(world: Any, session: Session) -> None:
                from ..ecs.scene_file import load_world

                load_world(path, world)

            app.on_open(load)


class PerfPlugin(Plugin):
    """The run's perf lines (once a second headless, and the closing one); `overlay=True` also
    draws the Perf window (frame times, CPU, GPU) over the game."""

    def __init__(self, overlay: bool = False) -> None:
        self.overlay = overlay

    def build(self, app: App) -> None:
        app.perf_lines = True
        app.perf_overlay = self.overlay


class EditorPlugin(Plugin):
    """The ImGui editor (scene, inspector, entity browser, Perf) over the game."""

    def build(self, app: App) -> None:
        app.editor = True


PluginLike = Any  # a Plugin class or instance, a function of the App, or a PluginGroup


def plugin_key(plugin: PluginLike) -> Any:
    """What makes two plugins the same one: the class, or the function."""
    return plugin if isinstance(plugin, type) or not hasattr(plugin, "build") else type(plugin)


def plugin_name(plugin: PluginLike) -> str:
    key = plugin_key(plugin)
    return getattr(key, "__qualname__", None) or repr(key)


class PluginGroup:
    """Plugins added together, in order. `without(P)` and `set(P(...))` give a new group."""

    def __init__(self, *plugins: PluginLike, name: str = "PluginGroup") -> None:
        self.plugins = tuple(plugins)
        self.name = name

    def __iter__(self) -> Iterator[PluginLike]:
        return iter(self.plugins)

    def _find(self, plugin: PluginLike, verb: str) -> int:
        key = plugin_key(plugin)
        for i, have in enumerate(self.plugins):
            if plugin_key(have) == key:
                return i
        names = ", ".join(plugin_name(p) for p in self.plugins)
        raise UsageError(f"{self.name}.{verb}({plugin_name(plugin)}): it has no such plugin; it has {names}")

    def without(self, *plugins: PluginLike) -> PluginGroup:
        """This group less `plugins` (classes or functions)."""
        kept = list(self.plugins)
        for plugin in plugins:
            del kept[PluginGroup(*kept, name=self.name)._find(plugin, "without")]
        return PluginGroup(*kept, name=self.name)

    def set(self, *plugins: PluginLike) -> PluginGroup:
        """This group with each of `plugins` in the place of the one of its class."""
        kept = list(self.plugins)
        for plugin in plugins:
            kept[self._find(plugin, "set")] = plugin
        return PluginGroup(*kept, name=self.name)

    def __repr__(self) -> str:
        return f"{self.name}({', '.join(plugin_name(p) for p in self.plugins)})"


def apply_plugin(app: App, plugin: PluginLike) -> None:
    """Build one plugin into `app` (a class is made with no arguments first)."""
    if isinstance(plugin, type):
        if not callable(getattr(plugin, "build", None)):
            raise UsageError(f"{plugin.__qualname__} is not a plugin: a plugin class has a build(app) method")
        plugin = plugin()
    build: Callable[[App], Any] | None = getattr(plugin, "build", None)
    if build is None and callable(plugin):
        build = plugin
    if build is None:
        raise UsageError(f"not a plugin: {plugin!r:.80} (a function of the App, or a class with build(app))")
    build(app)


class ScheduleOnly:
    """What plugins that only add systems build into, for a schedule without an App."""

    def __init__(self) -> None:
        self.schedule = Schedule(STAGES)

    def add_systems(self, stage: str, *systems: System) -> None:
        for system in systems:
            self.schedule.add(system, stage)

    def on_open(self, hook: Any) -> None:
        pass  # a plain schedule opens no run


def schedule_of(group: PluginGroup) -> Schedule:
    """The systems of `group`'s plugins, in order: the demo scenes' schedule is SCENE_PLUGINS'."""
    target = ScheduleOnly()
    for plugin in group:
        apply_plugin(target, plugin)
    return target.schedule


# the systems the demo scenes run (scenes.default_schedule), in their order
SCENE_PLUGINS = PluginGroup(
    TimePlugin, MotionPlugin, CameraControlPlugin, TransformPlugin, HierarchyPlugin, name="SCENE_PLUGINS"
)
DefaultPlugins = PluginGroup(
    TimePlugin,
    InputPlugin,
    WindowPlugin,
    RenderPlugin,
    MotionPlugin,
    AnimationPlugin,
    CameraControlPlugin,
    TransformPlugin,
    HierarchyPlugin,
    PickingPlugin,
    ScenePlugin,
    PerfPlugin,
    name="DefaultPlugins",
)
MinimalPlugins = PluginGroup(
    TimePlugin, MotionPlugin, AnimationPlugin, TransformPlugin, HierarchyPlugin, name="MinimalPlugins"
)
