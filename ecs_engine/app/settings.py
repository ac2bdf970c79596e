"""What a run is asked to do.

`RunOptions` is fixed for the whole run (frozen: a change is a new value, `dataclasses.replace`).
`Settings` are the few things that may change while it runs (the editor's controls); the
`Session` holds the current ones and is the one owner of each: the thread count lives in the
worker pool, the mode and recorder in the renderer's path, the present mode in the swapchain.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import psutil

from ..errors import UsageError
from ..jobs import default_threads
from ..render.config import RenderConfig, check
from ..render.config.flags import RUN_FIELDS
from ..render.frame.renderer import default_recorder
from .scenes import SEED_SCENES

FIXED_DT = 1.0 / 60.0  # headless runs: one fixed step a frame, so a run is reproducible frame for frame
SIM_STEP = 1.0 / 120.0  # windowed runs: the fixed simulation step (ecs.FixedTimestep)
MAX_DT = 0.1  # a hitch (dragging the window, a breakpoint) must not fling the camera (per-frame stages)
HEADLESS_FALLBACK_FRAMES = 300  # no display for a windowed run: this many frames headless instead
HEADLESS_FRAMES = {"demo": 1, "editor": 1, "play": 600}  # a --headless run without --frames (play: an App's too)


@dataclass
class Settings:
    scene: str
    # the render settings' names are render/config/__init__.py's enums (Mode, Culling, Fill, ToneMap...)
    mode: str
    recorder: str  # config.Recorder (the indirect mode records on the GPU: kept for switching back)
    threads: int  # worker pool size, counting the main thread
    culling: str  # config.Culling
    present: str | None  # fifo | mailbox | immediate; None: headless, no swapchain
    fill: str = "solid"  # config.Fill
    tone_map: str = "clamp"  # config.ToneMap (render/passes/tone_map.py)
    exposure: float = 0.0  # stops
    light_culling: str = "auto"  # config.LightCulling (render/lighting/clusters.py)
    transparency: str = "sorted"  # config.Transparency (render/passes/oit.py)
    lod: bool = True  # levels of detail by projected size (the indirect mode: render/assets/mesh_lod.py)
    shadow_method: str = "maps"  # config.Shadows (render/raytracing/shadows.py)
    shadow_denoise: bool = True  # ray-traced soft shadows filtered (render/raytracing/denoise.py)
    frame_reuse: bool = True  # a frame that would record what its slot recorded submits that (render/frame/replay.py)
    post: frozenset[str] = frozenset()  # the post effects on (render/post/registry.py's names)


@dataclass(frozen=True)
class RunOptions:
    """A run. `scene`, `mode`, `recorder`, `threads`, `culling` and `present` are where the
    run starts (see `settings()`); the editor may change them later."""

    scene: str = "grid100"
    path: str | None = None
    headless: bool = True
    frames: int | None = None  # None: until the window closes (headless: 1)
    screenshot: str | None = None
    width: int = 1280
    height: int = 720
    validate: bool = False
    present: str = "fifo"
    quiet: bool = False
    mode: str = "instanced"  # the render settings: render/config/__init__.py's names (render_config())
    threads: int | None = None  # None: all cores
    culling: str = "frustum"
    lod: bool = True  # --no-lod: the indirect mode draws every mesh in full
    fill: str = "solid"
    tone_map: str = "clamp"
    exposure: float = 0.0  # stops: the HDR colour times 2^exposure before the tone map
    msaa: int = 1  # samples per pixel of the scene (1, 2, 4, 8), fixed for the run
    anisotropy: int | None = None  # textures' maximum anisotropy (1: off; None: the device's, up to 16)
    light_culling: str = "auto"
    transparency: str = "sorted"  # blended materials: sorted, or weighted (order-independent)
    lights: int | None = None  # the lights scene's light count (None: its default, 1,024)
    shadows: bool = True  # the shadows scene's lights cast (--no-shadows: none do)
    shadow_method: str = "maps"  # config.Shadows: how shadows are drawn (render/raytracing/shadows.py)
    shadow_denoise: bool = True  # --no-shadow-denoise: ray-traced soft shadows unfiltered
    post: frozenset[str] = frozenset()  # --post bloom,fxaa: the post effects (render/post/registry.py)
    frame_reuse: bool = True  # --no-frame-reuse: every frame recorded (render/frame/replay.py)
    chunk_rows: int | None = None  # rows per render job (None: about one per thread, frame_data.MIN_CHUNK_ROWS)
    recorder: str | None = None  # config.Recorder (None: native when numba is there)
    entities: int = 10_000  # the scaling scene's entity count
    perf_json: str | None = None  # write every frame's perf samples here at the end
    trace: str | None = None  # write a Chrome trace of systems, jobs and GPU passes here at the end (app/trace.py)
    input_script: str | None = None  # input by frame to replay (app/input_script.py)
    record_input: str | None = None  # write the run's input by frame here at the end
    audio_out: str | None = None  # capture the sound (AudioPlugin) to this WAV file, frame by frame
    force: bool = False  # the outputs may replace a file of another kind (app/output_files.py)
    editor: bool = False  # the ImGui editor and Perf window (headless: drawn into the image)
    perf_lines: bool = True  # the perf lines (once a second headless, and the closing one): an App's PerfPlugin
    scenes: tuple[str, ...] = SEED_SCENES  # the editor's scene switcher

    # the command-line flags every rendering command shares (cli.render_flags), by field name
    FLAGS: ClassVar[tuple[str, ...]] = (
        "headless",
        "frames",
        "screenshot",
        "width",
        "height",
        "validate",
        "present",
        "mode",
        "threads",
        "culling",
        "lod",
        "fill",
        "tone_map",
        "exposure",
        "msaa",
        "anisotropy",
        "light_culling",
        "transparency",
        "shadow_method",
        "shadow_denoise",
        "post",
        "frame_reuse",
        "recorder",
        "perf_json",
        "trace",
        "input_script",
        "record_input",
        "audio_out",
        "force",
    )

    @classmethod
    def from_flags(cls, args: Any, **fields: Any) -> RunOptions:
        """The options a command's parsed render flags give, plus its own `fields`."""
        return cls(**{name: getattr(args, name) for name in cls.FLAGS}, **fields)

    def __post_init__(self) -> None:
        check_threads(self.threads)
        check_entities(self.entities)
        check(self.render_config())  # the configuration's own rules; the device's once it is open
        if self.lights is not None and not 0 <= self.lights <= MAX_LIGHTS:
            raise UsageError(f"--lights {self.lights}: from 0 to {MAX_LIGHTS:,}")

    def render_config(self) -> RenderConfig:
        """The render settings the run starts with, as one value (UsageError for a bad one)."""
        names = [f.name for f in dataclasses.fields(RenderConfig)]
        return RenderConfig.from_strings(**{n: getattr(self, RUN_FIELDS.get(n, n)) for n in names})

    def settings(self) -> Settings:
        return Settings(
            scene=self.scene,
            mode=self.mode,
            recorder=self.recorder or default_recorder(),
            threads=self.threads or default_threads(),
            culling=self.culling,
            present=None if self.headless else self.present,
            fill=self.fill,
            tone_map=self.tone_map,
            exposure=self.exposure,
            light_culling=self.light_culling,
            transparency=self.transparency,
            lod=self.lod,
            shadow_method=self.shadow_method,
            shadow_denoise=self.shadow_denoise,
            frame_reuse=self.frame_reuse,
            post=frozenset(self.post),
        )


# Bytes one scaling-scene entity needs at its peak, measured from its columns: Transform (80),
# Velocity and AngularVelocity (48), Mesh (8), ModelMatrix (64), the id column and entity index
# (28), the arrays its spawn call builds (~150), and two frame slots of 64-byte instance rows.
BYTES_PER_ENTITY = 500
MAX_ENTITIES = (1 << 32) - 1  # entity slots are 32-bit
MAX_LIGHTS = 1 << 20  # the lights scene: a million lights is a scene no one draws interactively


def max_threads() -> int:
    """More threads than this only add hand-off cost (the jobs are per core)."""
    return max(64, 4 * default_threads())


def check_threads(threads: int | None) -> None:
    if threads is not None and not 1 <= threads <= max_threads():
        raise UsageError(
            f"--threads {threads}: choose 1 to {max_threads()} (at most 4 per core, "
            f"{default_threads()} cores here, or 64)"
        )


def check_entities(entities: int, available: int | None = None) -> None:
    """Refuse a count the machine cannot hold before anything is allocated."""
    free = psutil.virtual_memory().available if available is None else available
    need = entities * BYTES_PER_ENTITY
    if need > free:
        raise UsageError(
            f"--entities {entities:,} needs about {_size(need)} of memory "
            f"({BYTES_PER_ENTITY} bytes each); {_size(free)} is free"
        )
    if entities > MAX_ENTITIES:
        raise UsageError(f"--entities {entities:,}: at most {MAX_ENTITIES:,} (entity slots are 32-bit)")


def _size(n: float) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:,.0f} {unit}" if unit == "bytes" else f"{n:,.1f} {unit}"
        n /= 1024
    return f"{n:.1f} PiB"
