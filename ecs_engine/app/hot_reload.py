"""Hot reload (`ecs-engine play game.py --watch`): a game's changed code goes into the running
App between two frames; the world, its entities and resources stay as they are. The textures and
meshes it loaded from files are reloaded too (asset_reload.py), and in a run that draws, the
engine's shaders (shader_reload.py).

When the game's file changes (app/file_watch.py polls it at most every 0.25 s, between frames):
1. its source is compiled and run into a fresh module object (not from a bytecode cache: an
   edit in the same second with the same size must not be missed);
2. classes the world holds state in keep their old class: a Component class (the world's
   columns are the old class's), a class that keys a world resource and a state's Enum (the
   State resource holds its members). The new module's name
   is bound to the old class, so its systems find the world's data. If such a class's fields
   changed, the reload is refused: the columns cannot change shape under running entities;
3. the new module's build(app) runs against a fresh App that never runs (a recording stand-in:
   its plugins and resources are thrown away), and the systems defined in the game's module are
   taken from it by name: one of the same name is replaced in place (App.replace_system), a new
   one is added at the end of its stage, one gone from the source is removed. Startup systems
   do not run again (the world they built is the one kept); the engine's own systems (from
   plugins) are not touched.

Any failure in 1-3 (a syntax error, an exception on import or in build, a component's fields
changed) is one line on stderr naming the file and line, also shown in the editor, and nothing
changes: the old systems keep running. `--debug` adds the traceback.

The systems a reload puts in are Guarded: one that raises in a later frame is caught, and at the
next frame boundary the systems before the reload come back, with one line saying which raised.
"""

from __future__ import annotations

import importlib.util
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field, fields, is_dataclass
from enum import Enum
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from ..ecs.schedule import System
from ..ecs.schema import Component, object_component
from ..errors import UsageError
from .asset_reload import AssetReload
from .file_watch import POLL_INTERVAL_S, FileWatch
from .shader_reload import ShaderReload

if TYPE_CHECKING:
    from .app import App


class ReloadRefused(Exception):
    """A reload that changes nothing; the message is the one line that says why."""


@dataclass
class Plan:
    """What a reload does to the running App, worked out before anything changes."""

    module: ModuleType
    replace: list[tuple[str, System]] = field(default_factory=list)
    add: list[tuple[str, System]] = field(default_factory=list)  # (stage, system)
    remove: list[str] = field(default_factory=list)
    new_startup: list[str] = field(default_factory=list)  # startup systems that will not run


@dataclass
class Undo:
    """What brings back the code before a reload: its module and systems."""

    module: ModuleType
    replaced: list[tuple[str, System]]  # (name, the system before)
    added: list[str]
    removed: list[tuple[str, System]]  # (stage, the system)


class Guarded(System):
    """A system a reload put in: an exception from it is caught and brings back the code before
    the reload at the next frame boundary (HotReload.between_frames)."""

    def __init__(self, inner: System, failed: Callable[[Guarded, Exception], None]) -> None:
        super().__init__(None, None, inner.name, inner.run_if)
        self.reads, self.writes, self.exclusive = inner.reads, inner.writes, inner.exclusive
        self.inner, self.failed = inner, failed

    def run(self, world: Any, dt: float) -> None:
        try:
            self.inner.run(world, dt)
        except Exception as exc:
            self.failed(self, exc)


class HotReload:
    """Watches the game module `module` that built `app` (shown as `shown` in messages) and
    reloads it between frames. `install()` hooks it into the App's run."""

    def __init__(
        self,
        app: App,
        module: ModuleType,
        shown: str | None = None,
        *,
        debug: bool = False,
        interval: float = POLL_INTERVAL_S,
        shader_dir: Path | None = None,
        say: Callable[[str], None] = print,
        warn: Callable[[str], None] = lambda line: print(line, file=sys.stderr),
    ) -> None:
        if getattr(module, "__file__", None) is None:
            raise UsageError(f"--watch: {module.__name__} has no source file to watch")
        self.app = app
        self.module = module
        self.path = Path(str(module.__file__)).resolve()
        self.shown = shown or str(module.__file__)
        self.debug = debug
        self.say, self.warn = say, warn
        self.files = FileWatch(interval)
        self.files.watch([self.path])
        self.assets = AssetReload(app.world, self.files)
        self.shaders = ShaderReload(self.files, shader_dir) if app.renders else None
        self.reloads = 0  # reloads that went in
        self.rolled_back = 0  # reloads taken back: a new system raised
        self._undo: Undo | None = None
        self._raised: tuple[str, Exception] | None = None  # a Guarded system's, since the last frame boundary
        self.failures = 0  # reloads refused
        self.last_message = ""

    def install(self) -> HotReload:
        self.app.on_frame_end(self.between_frames)
        return self

    def between_frames(self, session: Any, editor: Any) -> None:
        if self._raised is not None:
            self.report(self.roll_back(), editor)
        self.assets.follow()
        changed = self.files.changed()
        if self.path in changed:
            self.report(self.reload(), editor)
        if not changed:
            return
        assets = [path for path in changed if path != self.path]
        outcomes = self.assets.reload(assets)
        if self.shaders is not None:
            outcomes += self.shaders.reload(assets, session.renderer)
        for outcome in outcomes:
            self.report(outcome, editor)

    def report(self, outcome: tuple[bool, str], editor: Any) -> None:
        went_in, line = outcome
        self.last_message = line
        (self.say if went_in else self.warn)(line)
        if editor is not None:
            editor.refused(line)  # the editor's status line

    # ------------------------------------------------------------------------ reloading
    def reload(self) -> tuple[bool, str]:
        """Reload the game's module now: (True, what changed) or (False, why nothing did)."""
        start = time.perf_counter()
        try:
            plan = self.plan()
        except ReloadRefused as exc:
            self.failures += 1
            if self.debug and exc.__cause__ is not None:
                traceback.print_exception(exc.__cause__)
            return False, f"hot reload: {exc}; the old code keeps running"
        self._undo = Undo(
            self.module,
            [(name, self.app.system(name)) for name, _ in plan.replace],
            [made.name for _, made in plan.add],
            [(self.app.systems()[name], self.app.system(name)) for name in plan.remove],
        )
        for name in plan.remove:
            self.app.remove_system(name)
        for name, made in plan.replace:
            self.app.replace_system(name, Guarded(made, self._failed))
        for stage, made in plan.add:
            self.app.add_systems(stage, Guarded(made, self._failed))
        self.module = plan.module
        sys.modules[self.module.__name__] = self.module
        self.reloads += 1
        parts = [f"{len(plan.replace)} system{'s' if len(plan.replace) != 1 else ''} replaced"]
        if plan.add:
            parts.append("added " + ", ".join(made.name for _, made in plan.add))
        if plan.remove:
            parts.append("removed " + ", ".join(plan.remove))
        if plan.new_startup:
            parts.append(f"startup systems do not run again ({', '.join(plan.new_startup)} is new: restart to run it)")
        took = (time.perf_counter() - start) * 1e3
        return True, f"hot reload: {self.shown}: {'; '.join(parts)} ({took:.0f} ms)"

    def _failed(self, made: Guarded, exc: Exception) -> None:
        if self._raised is None:  # the first one says why
            self._raised = (made.name, exc)

    def roll_back(self) -> tuple[bool, str]:
        """The systems and module before the last reload, in place of those a reload put in
        (one of which raised)."""
        assert self._raised is not None and self._undo is not None
        (name, exc), undo = self._raised, self._undo
        self._raised = self._undo = None
        for added in undo.added:
            self.app.remove_system(added)
        for replaced, old in undo.replaced:
            self.app.replace_system(replaced, old)
        for stage, old in undo.removed:
            self.app.add_systems(stage, old)
        self.module = undo.module
        sys.modules[self.module.__name__] = self.module
        self.rolled_back += 1
        if self.debug:
            traceback.print_exception(exc)
        return False, f"hot reload: {self._where(exc, f'system {name} raised')}; back to the code before the reload"

    def plan(self) -> Plan:
        module = self._execute()
        kept = self._keep_state_classes(module)
        stand_in = type(self.app)(name=self.app.name)
        stand_in.options = self.app.options
        try:
            module.build(stand_in)
        except Exception as exc:
            raise ReloadRefused(self._where(exc, "build(app) raised")) from exc
        new = self._game_systems(stand_in)
        old = self._game_systems(self.app)
        for _, made in new.values():  # declared while the module ran, before the old classes were put back
            made.reads, made.writes = _mapped(made.reads, kept), _mapped(made.writes, kept)
        plan = Plan(module)
        plan.new_startup = [n for n, (stage, _) in new.items() if stage == "startup" and n not in old]
        for name, (stage, made) in new.items():
            if stage == "startup":
                continue
            if name in old and old[name][0] == stage:
                plan.replace.append((name, made))
            else:
                if name in old:
                    plan.remove.append(name)  # moved to another stage: out, then in at its end
                plan.add.append((stage, made))
        plan.remove += [n for n, (stage, _) in old.items() if n not in new and stage != "startup"]
        return plan

    def _execute(self) -> ModuleType:
        """The game's source run into a fresh module of the same name."""
        name = self.module.__name__
        try:
            source = self.path.read_bytes()
        except OSError as exc:
            raise ReloadRefused(f"{self.shown}: cannot be read: {exc.strerror or exc}") from exc
        spec = importlib.util.spec_from_file_location(name, self.path)
        assert spec is not None
        module = importlib.util.module_from_spec(spec)
        old = sys.modules.get(name)
        sys.modules[name] = module  # dataclasses and the like look their module up while it runs
        try:
            exec(compile(source, str(self.path), "exec"), module.__dict__)
        except SyntaxError as exc:
            raise ReloadRefused(f"{self.shown}:{exc.lineno}: syntax error: {exc.msg}") from exc
        except Exception as exc:
            raise ReloadRefused(self._where(exc, "importing it raised")) from exc
        finally:
            if old is not None:
                sys.modules[name] = old  # until the reload goes in
        return module

    def _where(self, exc: BaseException, what: str) -> str:
        """`file:line: what Type: message`, the line the innermost in the game's file."""
        lines = [f.lineno for f in traceback.extract_tb(exc.__traceback__) if Path(f.filename) == self.path]
        at = f"{self.shown}:{lines[-1]}" if lines else self.shown
        text = " ".join(str(exc).split())
        return f"{at}: {what} {type(exc).__name__}" + (f": {text}" if text else "")

    def _keep_state_classes(self, module: ModuleType) -> dict[type, type]:
        """The new module's names of Component classes and resource keys bound to the old
        classes, whose instances the world holds; refused if their fields changed. Returns
        {new class: old class}."""
        resources = self.app.world.resources
        name = self.module.__name__
        kept: dict[type, type] = {}
        for attr, new in list(vars(module).items()):
            old = vars(self.module).get(attr)
            if not (isinstance(new, type) and isinstance(old, type)) or new.__module__ != name:
                continue
            if old.__module__ != name:
                continue
            if issubclass(old, Component):
                kind = "component"
            elif any(key is old for key in resources):
                kind = "resource"
            elif issubclass(old, Enum) and any(getattr(key, "kind", None) is old for key in resources):
                kind = "state"  # State[Kind] holds the old class's members: in_state must ask with them
            else:
                continue  # a class the world holds nothing of: the new one is used
            was, now = _layout(old), _layout(new)
            if was != now:
                raise ReloadRefused(
                    f"{self.shown}: {kind} {attr}'s fields changed ({', '.join(was) or 'none'} -> "
                    f"{', '.join(now) or 'none'}): the world holds it as it was; restart to use the new fields"
                )
            setattr(module, attr, old)
            kept[new] = old
        return kept

    def _game_systems(self, app: App) -> dict[str, tuple[str, System]]:
        """The systems of `app` written in the game's module: name -> (stage, system)."""
        found: dict[str, tuple[str, System]] = {}
        for name, stage in app.systems().items():
            made = app.system(name)
            if _module_of(made) == self.module.__name__:
                found[name] = (stage, made)
        return found


def _mapped(types: frozenset[type] | None, kept: dict[type, type]) -> frozenset[type] | None:
    """`types` (a system's reads or writes) with the old classes for the new: a plain class
    declared there stands as its object store (ecs/schema.object_component)."""
    if types is None:
        return None
    stores = {object_component(n): object_component(o) for n, o in kept.items() if not issubclass(o, Component)}
    return frozenset(kept.get(t, stores.get(t, t)) for t in types)


def _module_of(made: System) -> str | None:
    if isinstance(made, Guarded):
        made = made.inner
    fn = getattr(made, "fn", None)
    return getattr(fn, "__module__", None) if fn is not None else type(made).__module__


def _layout(cls: type) -> list[str]:
    """A class's fields as the world stores them: a Component's columns, a dataclass's fields."""
    if issubclass(cls, Component):
        return [f"{n}: {f.dtype}{list(f.shape) if f.shape else ''}" for n, f in cls.__fields__.items()]
    if is_dataclass(cls):
        return [f.name for f in fields(cls)]
    if issubclass(cls, Enum):
        return [f"{m.name}={m.value!r}" for m in cls]
    return []
