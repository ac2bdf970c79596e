"""A session: everything one run draws with and updates, in one owner.

It owns the Vulkan objects (opened by a frame source: offscreen or a window), the mesh
registry, the worker pool, the world with its schedule, and the renderer. `apply(settings)`
makes live changes (mode, recorder, threads, culling, present mode, scene) by changing their one
owner each: the renderer's path, the pool (resized in place), the swapchain, a new world. The
current settings are read back from those owners, never kept twice.

A scene opened while running (the editor's File > Open, its scene switcher) may load and still
fail in its first frames (a Parent loop, a missing environment file, a Mesh handle naming no
mesh): the scene before it is kept for `PROBATION_FRAMES` frames, and `roll_back` brings it back,
with its world untouched; the renderer follows whichever world it is given (its environment
image, materials and shadow maps are matched to the world each frame).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from ..components.camera import active_camera
from ..ecs.errors import EcsError
from ..ecs.scene_file import load_world
from ..ecs.schedule import Schedule
from ..ecs.timestep import FixedTimestep
from ..ecs.world import World
from ..errors import UsageError
from ..gpu.device import Device
from ..gpu.instance import Instance
from ..jobs import JobPool
from ..render.assets.mesh_registry import MeshRegistry
from ..render.assets.meshes import Meshes
from ..render.assets.scene_assets import scene_codecs
from ..render.config import Caps, RenderConfig, check
from ..render.frame.renderer import Renderer
from .scenes import default_schedule, is_scene_file, scene_builder, scene_systems
from .settings import RunOptions, Settings

PROBATION_FRAMES = 3  # frames a newly opened scene must run before the one before it is let go


@dataclass
class Gpu:
    """The Vulkan objects of a run, opened by its frame source."""

    instance: Instance
    device: Device
    target: Any  # gpu.offscreen.OffscreenTarget or gpu.swapchain.Swapchain
    meshes: MeshRegistry


@dataclass
class FrameTarget:
    """Where one frame goes: the renderer's `render` arguments, and the source's bookkeeping."""

    dt: float  # seconds of simulation this frame
    framebuffer: Any = None  # None: the offscreen target's own
    extent: tuple[int, int] | None = None
    wait: Any = None  # semaphore the frame waits for (the acquired swapchain image)
    signal: Any = None  # semaphore it signals (for presenting)
    readback: bool = False  # wait for the frame and copy the image to the host
    waited_ms: float = 0.0  # blocked in the source (acquire), not CPU work
    image: int = 0  # the swapchain image index
    suboptimal: bool = False


class FrameSource(Protocol):
    """Offscreen (app/offscreen.py) or a window (app/window.py)."""

    clock: FixedTimestep
    max_frame_dt: float
    window: Any  # the GLFW window, or None
    input: Any  # the InputState resource keys go to, or None
    instance: Instance | None  # once opened; its validation messages outlive the run
    minimised_waits: int  # loop turns spent minimised (0 offscreen)

    @property
    def recreations(self) -> int:
        """Swapchain recreations (0 offscreen)."""
        ...

    @property
    def present_mode(self) -> str | None:
        """fifo, mailbox or immediate; None without a swapchain."""
        ...

    def check_present(self, present: str) -> None:
        """Raise UsageError unless `present` can be used."""
        ...

    def set_present(self, present: str) -> None: ...

    def pixels(self) -> Any:
        """The last frame's image (RGBA), where the source read it back; else None."""
        ...

    def validation_messages(self) -> list[str]:
        """What the validation layers reported during this source's run."""
        ...

    def open(self, options: RunOptions) -> Gpu: ...

    def attach(self, session: Session) -> None: ...

    def running(self, frames_done: int) -> bool: ...

    def abandon(self, session: Session, target: FrameTarget) -> None:
        """A frame that failed after `begin` (a scene rolled back): give back what it took."""
        ...

    def request_close(self) -> None:
        """End the run after this frame (Esc), as closing the window does."""
        ...

    def begin(self, session: Session, frames_done: int) -> FrameTarget | None: ...

    def end(self, session: Session, target: FrameTarget) -> None: ...

    def describe(self, session: Session) -> str: ...

    def close(self) -> None: ...


def one_line(exc: BaseException) -> str:
    """An error as one line: the message of one a user can cause, else its type too."""
    text = " ".join(str(exc).split())
    if isinstance(exc, (UsageError, EcsError, ValueError)) and text:
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class Session:
    def __init__(self, options: RunOptions, source: FrameSource) -> None:
        self.options = options
        self.source = source
        # called with the new world whenever a scene is loaded (the window puts its InputState there)
        self.on_world: list[Callable[[World], None]] = []
        try:
            self.gpu = source.open(options)
            start = options.settings()
            self.pool = JobPool(start.threads)
            self.renderer = self._make_renderer(start)
            self.renderer.replay.enabled = start.frame_reuse
            self.scene = start.scene
            self.world, self.schedule = self._open(start.scene, options.path)
            self._previous: tuple[str, World, Schedule] | None = None  # the scene before, on probation
            self.probation = 0
            source.attach(self)
        except BaseException:
            self.close()
            raise

    def _make_renderer(self, start: Settings) -> Renderer:
        options = self.options
        return Renderer(
            self.gpu.device,
            self.gpu.target,
            self.gpu.meshes,
            mode=start.mode,
            recorder=start.recorder,
            jobs=self.pool,
            culling=start.culling,
            chunk_rows=options.chunk_rows,
            fill=start.fill,
            tone_map=start.tone_map,
            exposure=start.exposure,
            light_culling=start.light_culling,
            transparency=start.transparency,
            lod=start.lod,
            shadows=start.shadow_method,
            shadow_denoise=start.shadow_denoise,
            anisotropy=options.anisotropy,
            post=start.post,
        )

    @property
    def device(self) -> Device:
        return self.gpu.device

    @property
    def settings(self) -> Settings:
        """The settings in force, read from their owners."""
        return Settings(
            scene=self.scene,
            mode=self.renderer.mode,
            recorder=self.renderer.cpu_recorder,
            threads=self.pool.threads,
            culling=self.renderer.culling,
            present=self.source.present_mode,
            fill=self.renderer.fill,
            tone_map=self.renderer.tone_map,
            exposure=self.renderer.exposure,
            light_culling=self.renderer.light_culling,
            transparency=self.renderer.transparency,
            lod=self.renderer.lod,
            shadow_method=self.renderer.shadow_method,
            shadow_denoise=self.renderer.shadow_denoise,
            frame_reuse=self.renderer.replay.enabled,
            post=frozenset(getattr(self.renderer, "post_effects", ())),  # (a simulation has none)
        )

    def _build(self, scene: str, path: str | None) -> tuple[World, Schedule]:
        """A new world for `scene` (a demo scene's name or a scene file's path; sharing the run's
        pool and meshes) and its schedule."""
        world = World()
        world.resources[JobPool] = self.pool
        world.resources[Meshes] = Meshes(self.gpu.meshes)  # world.save keeps the meshes by reference
        if is_scene_file(scene):
            load_world(scene, world, resources=scene_codecs(self.gpu.meshes))
            try:
                active_camera(world)  # a scene without one is refused here, not at the first frame
            except UsageError as exc:
                raise UsageError(f"scene file {scene}: {exc}") from None
        else:
            build = scene_builder(scene, self.options.entities, self.options.lights, self.options.shadows)
            build(world, self.gpu.meshes.add, path)
        schedule = default_schedule()
        for stage, system in scene_systems(scene):
            schedule.add(system, stage)
        return world, schedule

    def apply(self, wanted: Settings) -> None:
        """Make `wanted` the settings in force, changing only what differs. All or nothing: what
        can be refused (a thread count, a present mode or render path the device lacks, a scene
        that fails to build) is checked before anything changes."""
        renderer, pool, source = self.renderer, self.pool, self.source
        if wanted.threads < 1:
            raise ValueError(f"threads must be at least 1, got {wanted.threads}")
        present = wanted.present if wanted.present != source.present_mode else None
        if present is not None:
            source.check_present(present)
        # every render setting against the config's one table, as the renderer's constructor does
        config = RenderConfig.from_strings(
            mode=wanted.mode,
            recorder=wanted.recorder,
            culling=wanted.culling,
            fill=wanted.fill,
            tone_map=wanted.tone_map,
            exposure=wanted.exposure,
            light_culling=wanted.light_culling,
            transparency=wanted.transparency,
            lod=wanted.lod,
            shadows=wanted.shadow_method,
            shadow_denoise=wanted.shadow_denoise,
            msaa=renderer.target.samples,
            post=wanted.post,
        )
        check(config, Caps.of(self.device))
        culling = config.culling.value
        scene = self._open(wanted.scene) if wanted.scene != self.scene else None
        renderer.set_path(wanted.mode, wanted.recorder)  # checks, then swaps
        renderer.set_fill(wanted.fill)
        renderer.tone_map, renderer.exposure = wanted.tone_map, float(wanted.exposure)
        renderer.light_culling = wanted.light_culling
        renderer.transparency = wanted.transparency
        renderer.set_shadow_method(wanted.shadow_method)
        renderer.shadow_denoise = wanted.shadow_denoise
        if frozenset(wanted.post) != frozenset(getattr(renderer, "post_effects", ())):
            renderer.set_post_effects(wanted.post)
        renderer.replay.enabled = wanted.frame_reuse
        renderer.culling, renderer.lod = culling, wanted.lod
        pool.resize(wanted.threads)
        renderer.ensure_output()  # HDR colour or not, as the tone map and exposure now need
        if present is not None:
            source.set_present(present)
        if scene is not None:
            self._previous, self.probation = (self.scene, self.world, self.schedule), PROBATION_FRAMES
            self._switch(wanted.scene, *scene)

    def _open(self, scene: str, path: str | None = None) -> tuple[World, Schedule]:
        """`_build`, where whatever loading a scene file raises (a file the loader did not
        foresee, a scene without a camera) is a UsageError naming the file: bad input, which the
        editor refuses while going on with the scene it has."""
        try:
            return self._build(scene, path)
        except Exception as exc:
            if not is_scene_file(scene):
                raise
            if isinstance(exc, (UsageError, EcsError, ValueError)):
                if scene in str(exc):
                    raise
                raise UsageError(f"{scene}: {one_line(exc)}") from exc
            raise UsageError(f"{scene}: cannot be opened ({one_line(exc)})") from exc

    def _switch(self, scene: str, world: World, schedule: Schedule) -> None:
        self.world, self.schedule, self.scene = world, schedule, scene
        for hook in self.on_world:
            hook(self.world)

    def frame_done(self) -> None:
        """A frame ran: one fewer for a new scene to prove it can run."""
        if self.probation:
            self.probation -= 1
            if not self.probation:
                self._previous = None

    def roll_back(self) -> str | None:
        """The scene opened in the last PROBATION_FRAMES frames failed: the one before it again
        (its world as it was). The failed scene's name, or None when there is none to go back to
        (the failure is the run's)."""
        if self._previous is None:
            return None
        failed = self.scene
        scene, world, schedule = self._previous
        self._previous, self.probation = None, 0
        self._switch(scene, world, schedule)
        return failed

    def close(self) -> None:
        """Tear down in reverse: renderer, pool, then the source's Vulkan objects."""
        renderer, pool = self.__dict__.pop("renderer", None), self.__dict__.pop("pool", None)
        if renderer is not None:
            renderer.destroy()
        if pool is not None:
            pool.close()
        self.source.close()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
