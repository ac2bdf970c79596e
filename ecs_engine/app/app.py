"""`App`: the one public way to run a game. It holds a world and a schedule, is made of plugins
(plugins.py), and runs through the engine's one run loop (loop.py) in a Session:

    app = App(title="Catch", size=(1280, 720))
    app.add_plugins(DefaultPlugins)
    app.insert_resource(Score())
    app.add_startup_systems(setup)            # once, before the first frame (meshes are there)
    app.add_systems("update", move_paddle, catch)
    app.run()                                 # until the window closes (or Esc)
    app.run(frames=120, headless=True, screenshot="catch.png")

A game module is a file or module with `build(app)`; `ecs-engine play game.py` makes the App,
calls it and runs it with the command line's flags (game_module.py). Every system has a name
(a function's own name, a System's `name`) unique in the App: `replace_system(name, new)` swaps
one in the running schedule at its place, which is how changed code goes in while a game runs
(app_systems.py holds the App's systems by name).

Nothing here runs per frame: systems are the schedule's own, resources are made when the run
opens (`on_open`), and a frame is the loop's.
"""

from __future__ import annotations

import argparse
import re
import sys
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import fields, replace
from enum import Enum
from typing import Any

from ..ecs.errors import EcsError
from ..ecs.scene_file import main_module_name
from ..ecs.schedule import Schedule, System
from ..ecs.states import init_state
from ..ecs.world import World
from ..errors import UsageError
from .app_systems import AppSystems, as_usage
from .plugins import STAGES, PluginGroup, PluginLike, apply_plugin, plugin_key, plugin_name
from .report import RunResult
from .settings import HEADLESS_FALLBACK_FRAMES, RunOptions
from .settings import HEADLESS_FRAMES as COMMAND_HEADLESS_FRAMES
from .window_resource import Window, check_size

HEADLESS_FRAMES = COMMAND_HEADLESS_FRAMES["play"]  # a run without a window and without frames=

Hook = Callable[[World, Any], None]  # (the App's world, the Session) when the run opens
FrameHook = Callable[[Any, Any], None]  # (the Session, the editor or None) between two frames


class App(AppSystems):
    def __init__(self, title: str | None = None, size: tuple[int, int] = (1280, 720), *, name: str | None = None):
        # what names the run (its first line, its input-NAME.json, NAME.png): the title's words,
        # else the script's module name (python catch.py: catch, as `ecs-engine play catch.py`)
        self.name = name or _slug(title or "") or (main_module_name() or "").rpartition(".")[2] or "game"
        self.world = World()
        self.schedule = Schedule(STAGES)
        self.window = self.world.resources[Window] = Window(title or self.name, size)
        self.options = argparse.Namespace()  # a game module's own command-line options (add_arguments)
        self.renders = False  # RenderPlugin: a GPU draws the world
        self.windowed = False  # WindowPlugin: in a window when there is a display
        self.editor = False  # EditorPlugin
        self.perf_lines = False  # PerfPlugin: the run's perf lines
        self.perf_overlay = False
        self.scene_files: Any = None  # ScenePlugin: saves asked for by systems (scene_saves.SceneFiles)
        self.ui: list[Callable[[Any, World], Any]] = []  # draw(imgui, world) each UI frame
        self.summary: Callable[[World], str] | None = None
        self.started = False  # the startup systems ran (the run opened)
        self._plugins: dict[Any, str] = {}
        self._startup: list[System] = []
        self._open_hooks: list[Hook] = []
        self._frame_hooks: list[FrameHook] = []
        self._close_hooks: list[Callable[[World], Any]] = []
        self._where: dict[str, str] = {}  # system name -> its stage
        self._lists: dict[str, list[System]] = {}  # system name -> the list that runs it
        self._unnamed = 0  # lambdas numbered so far
        self._ran = False

    # ------------------------------------------------------------------ what the window says
    @property
    def title(self) -> str:
        return self.window.title

    @title.setter
    def title(self, value: str) -> None:
        self.window.title = value

    @property
    def size(self) -> tuple[int, int]:
        return self.window.size

    @size.setter
    def size(self, value: tuple[int, int]) -> None:
        self.window.size = check_size(value)

    # ------------------------------------------------------------------------- building
    def add_plugins(self, *plugins: PluginLike) -> App:
        """Plugins and plugin groups, built in order. A plugin added twice is an error."""
        for plugin in plugins:
            if isinstance(plugin, PluginGroup):
                self.add_plugins(*plugin)
                continue
            key = plugin_key(plugin)
            if key in self._plugins:
                raise UsageError(f"plugin {plugin_name(plugin)} is already added to this App")
            self._plugins[key] = plugin_name(plugin)
            apply_plugin(self, plugin)
        return self

    def has_plugin(self, plugin: PluginLike) -> bool:
        return plugin_key(plugin) in self._plugins

    def insert_resource(self, value: Any, key: Any = None) -> App:
        """`value` as the world's resource under `key` (default: its type)."""
        if key is None and isinstance(value, type):
            raise UsageError(f"insert_resource takes a value, such as {value.__name__}(), not the class itself")
        self.world.resources[type(value) if key is None else key] = value
        return self

    def add_actions(self, defaults: Mapping[str, Iterable[str]]) -> App:
        """The game's actions and their default bindings (systems.ActionMap), with the user's
        `input-<name>.json` in the config folder over them (app/bindings.py)."""
        from ..systems import ActionMap
        from .bindings import load_bindings

        self.world.resources[ActionMap] = load_bindings(defaults, self.name)
        return self

    # ------------------------------------------------- game structure (ecs/states.py, observers.py)
    def init_state(self, initial: Enum) -> App:
        """A state: `initial`'s Enum as the world's `State[Kind]`, entered on the first frame.
        Systems take `run_if=in_state(...)`; `request_state(world, value)` changes it."""
        as_usage(init_state, self.world, initial)
        return self

    def add_observer(self, trigger: Any, fn: Callable[[World, Any], Any], **named: Any) -> App:
        """`fn(world, trigger)` with every entity that gains (OnAdd), loses (OnRemove) or
        changes (OnChange) a component, in bulk, at each sync point (World.add_observer)."""
        as_usage(self.world.add_observer, trigger, fn, **named)
        return self

    # ---------------------------------------------------------------- hooks, UI, summary
    def on_open(self, hook: Hook) -> App:
        """`hook(world, session)` when the run opens, before the startup systems: for plugins
        whose resources need the GPU or the window (session.gpu, session.source)."""
        self._open_hooks.append(hook)
        return self

    def on_close(self, hook: Callable[[World], Any]) -> App:
        """`hook(world)` when the run ends (in reverse order of adding, as the run closes): for
        plugins that hold a device or a file open (a sound device, a capture)."""
        self._close_hooks.append(hook)
        return self

    def close_hooks(self) -> None:
        """Run the close hooks (AppSession.close): each once, the last added first."""
        hooks, self._close_hooks = self._close_hooks[::-1], []
        for hook in hooks:
            hook(self.world)

    def on_frame_end(self, hook: FrameHook) -> App:
        """`hook(session, editor)` between frames (the editor: None without one), where the
        schedule may change and GPU resources may be replaced (hot_reload.py). With no hook
        the run loop does nothing there."""
        self._frame_hooks.append(hook)
        return self

    def add_ui(self, draw: Callable[[Any, World], Any]) -> App:
        """`draw(imgui, world)` builds ImGui windows over the game each frame (a HUD); it may
        return {name: (x0, y0, x1, y1)} of its widgets (tests click them)."""
        if not callable(draw):
            raise UsageError(f"add_ui takes a function draw(imgui, world), not {draw!r:.80}")
        self.ui.append(draw)
        return self

    def set_summary(self, summary: Callable[[World], str]) -> App:
        """`summary(world)`: the line the run prints when its frames are done (a score), before
        its files are written."""
        self.summary = summary
        return self

    # ----------------------------------------------------------------------- opening
    def open(self, session: Any) -> tuple[World, Schedule]:
        """The world and schedule for `session` (AppSession): the first time, the engine's
        resources go in, the plugins' hooks run, then the startup systems."""
        if not self.started:
            from ..jobs import JobPool
            from ..render.assets.meshes import Meshes

            world = self.world
            world.resources[JobPool] = session.pool
            world.resources[Meshes] = Meshes(session.gpu.meshes)
            source = session.source
            self.window.bind(getattr(source, "glfw", None), source.window, source.request_close)
            for hook in self._open_hooks:
                hook(world, session)
            world.flush()
            for made in self._startup:
                world.run_system(made, 0.0)
                world.flush()  # the next startup system sees what this one spawned
            self.started = True
        return self.world, self.schedule

    # ------------------------------------------------------------------------ running
    def run(
        self,
        *,
        frames: int | None = None,
        headless: bool | None = None,
        screenshot: str | None = None,
        debug: bool = False,
        **options: Any,
    ) -> RunResult:
        """Run until the window closes (Esc), or `frames` frames. Without a window (asked,
        no display, or no WindowPlugin) it runs 600 frames unless told; with no display it
        says so and writes the last frame to `<name>.png`. `options`: any RunOptions field the
        command line sets (perf_json, input_script, record_input, validate, mode, threads...).
        Bad input is one line on stderr and SystemExit(2), Ctrl-C one line and SystemExit(130);
        `debug=True` shows the traceback of either."""
        from .entry_point import INTERRUPTED, interrupted

        try:
            wanted = self.run_options(frames=frames, headless=headless, screenshot=screenshot, **options)
            ready, source = self.prepare(wanted)
            return self.launch(ready, source)
        except KeyboardInterrupt:
            if debug:
                traceback.print_exc()
            interrupted(self.name)
            raise SystemExit(INTERRUPTED) from None
        except (UsageError, EcsError, ValueError, OSError) as exc:
            if debug:
                traceback.print_exc()
            print(f"{self.name}: error: {exc}", file=sys.stderr)
            raise SystemExit(2) from None

    def run_options(self, **given: Any) -> RunOptions:
        """RunOptions for this App from run()'s keyword arguments (None: not given)."""
        known = {f.name for f in fields(RunOptions)} & set(RunOptions.FLAGS)
        unknown = sorted(set(given) - known)
        if unknown:
            raise UsageError(f"App.run() has no option {unknown[0]!r}; it takes {', '.join(sorted(known))}")
        chosen = {k: v for k, v in given.items() if v is not None}
        width, height = self.size
        chosen.setdefault("width", width)
        chosen.setdefault("height", height)
        chosen.setdefault("headless", not self.windowed)
        return RunOptions(scene=self.name, editor=self.editor, scenes=(self.name,), **chosen)

    def prepare(self, options: RunOptions, headless_frames: int = HEADLESS_FRAMES) -> tuple[RunOptions, Any]:
        """The options as this App can run them, and the frame source: a simulation without
        RenderPlugin, offscreen when headless (or no WindowPlugin), else a window, or headless
        with a PNG when there is no display."""
        if self.editor and not self.renders:
            raise UsageError(f"{self.name} draws nothing (no RenderPlugin), so there is no editor to show it in")
        if not self.renders:
            if options.screenshot is not None:
                raise UsageError(f"{self.name} draws nothing (no RenderPlugin), so there is no screenshot to write")
            from .simulation import SimulationSource

            return replace(options, headless=True, frames=options.frames or headless_frames), SimulationSource()
        if options.headless or not self.windowed:
            return replace(options, headless=True, frames=options.frames or headless_frames), None
        from .output_files import check_run_files
        from .window import WindowSource, open_glfw

        check_run_files(options)  # before a window opens
        glfw = open_glfw()
        if glfw is not None:
            return options, WindowSource(glfw)
        shot = options.screenshot or f"{self.name}.png"
        options = replace(options, headless=True, frames=options.frames or HEADLESS_FALLBACK_FRAMES, screenshot=shot)
        check_run_files(options)
        print(
            f"no display found: running {self.name} headless for {options.frames} frames instead (last frame: {shot})"
        )
        return options, None

    def launch(self, options: RunOptions, source: Any = None) -> RunResult:
        """Run through the engine's loop with `options` as they are (prepare() made them), and
        say the validation layers' messages, if any. An App runs once."""
        from . import loop
        from .app_session import AppSession, AppUI
        from .report import report_validation

        if self._ran:
            raise UsageError("this App has run already: an App runs once (make another for another run)")
        self._ran = True
        if not self.perf_lines:
            options = replace(options, perf_lines=False)
        ui = None
        if (self.ui or self.perf_overlay) and not options.editor and self.renders:
            ui = AppUI
        summary = None if self.summary is None else (lambda session: self.summary(session.world))  # type: ignore[misc]
        between = self._between_frames if self._frame_hooks else None
        result = loop.run(
            options, source, make_session=lambda o, s: AppSession(self, o, s), ui=ui, summary=summary, between=between
        )
        report_validation(result)
        return result

    def _between_frames(self, session: Any, editor: Any) -> None:
        for hook in self._frame_hooks:
            hook(session, editor)


def _slug(title: str) -> str:
    """A name for files and the first line from a title: "Catch!" -> "catch"."""
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")
