"""Frame extraction: the world turned into the plain arrays one frame draws (camera, render
origin, view, frustum planes, lights, shadow casters, environment, materials, chunks of mesh
rows), with no GPU in sight.

The renderer records from a `FrameData` only, so what a frame will draw can be tested without a
device, and the world is read in one place: the extract stage, `FrameExtractor` calling the
functions of extract/ (one per part of the snapshot, each reading only the components and
resources it names, so that they can later run as systems of the parallel schedule). No other
render module reads the world (tests/test_extract_stage.py). Everything here is kept between
frames while its inputs are unchanged: a still scene of 100 cubes has a CPU budget of 250 us a
frame, and rebuilding matrices, planes and chunk lists would spend a good part of it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...components import render_origin
from ...components.camera import RenderLayers, active_camera
from ...components.camera_views import DEFAULT_LAYERS
from ...components.environment import Environment
from ...ecs.structural import structural
from ...ecs.world import World
from ...maths.culling import frustum_planes
from ..assets.materials import Materials
from ..config import Culling
from ..culling import METHODS, CullingMethod, TemporalCulling, check_culling, culling_name
from ..culling.temporal_culling import TemporalCuller
from ..frame.camera import CameraMatrices, camera_matrices, view_from_origin
from ..lighting.rows import DirectionalLights, PositionalLights
from .chunks import (
    MIN_CHUNK_ROWS,
    MODEL_COLUMN,
    NOT_CASTER,
    NOT_RECEIVER,
    Chunk,
    ChunkExtract,
    SetAsideRows,
    shadow_flags,
)
from .environment import extract_environment
from .lights import KeptPoints, LightKinds, extract_lights, light_kinds
from .materials import extract_materials
from .shadows import ShadowCasters, ShadowExtract
from .skins import deformed, extract_deform

# names older code imports from here (they live in extract/chunks.py)
__all__ = [
    "CULLING",
    "MIN_CHUNK_ROWS",
    "MODEL_COLUMN",
    "NOT_CASTER",
    "NOT_RECEIVER",
    "Chunk",
    "FrameData",
    "FrameExtractor",
    "SetAsideRows",
    "check_culling",
    "shadow_flags",
]

# the culling methods' names (render/culling/: what each decides, and where)
CULLING = Culling.names()


@dataclass
class FrameData:
    camera: CameraMatrices
    origin: np.ndarray  # float64: model matrices are relative to it
    origin_key: bytes
    view: np.ndarray  # float32 (4, 4): the camera's view for matrices relative to `origin`
    culling: CullingMethod  # what decided the planes and masks; the chunk jobs and GPU passes ask it
    planes: np.ndarray | None  # the planes the culling tests rows against (k, 4) float64; None: none
    lights: list[PositionalLights]  # per table of point or spot lights
    directional: list[DirectionalLights]
    light_count: int  # of every kind
    chunks: list[Chunk]
    candidates: int  # rows with a mesh in the chunks (opaque and masked materials), before culling
    set_aside: SetAsideRows | None = None  # None: no material is blended or has its own fill
    masks: dict[int, np.ndarray] | None = None  # per table id, the rows to draw, where the culling decided ahead
    shadows: ShadowCasters | None = None  # the lights with a Shadow (None: none has one)
    environment: Environment | None = None  # the world's Environment resource
    materials: Materials | None = None  # the world's Materials (or a default palette); None: not extracted
    # the skins' joint matrices' rows and the morph weights (K, 4) float32 (extract/skins.py); None: neither
    deform: np.ndarray | None = None

    def visible(self, chunk: Chunk) -> np.ndarray | None:
        """The rows of `chunk` to draw, where the culling decided ahead (temporal); else None."""
        if self.masks is None or chunk.table not in self.masks:
            return None
        return self.masks[chunk.table][chunk.start : chunk.start + len(chunk.handle)]

    @property
    def all_rows(self) -> int:
        """Rows with a mesh: the chunks', then the set-aside ones (a shadow view's rows: both cast)."""
        return self.candidates + (len(self.set_aside) if self.set_aside is not None else 0)


class FrameExtractor:
    """Turns a world into `FrameData` through the extract functions (extract/), keeping what
    each keeps between frames. A table's rows are cut into jobs of `chunk_rows`, or by default
    into about one job per thread of `threads()` (at least MIN_CHUNK_ROWS rows)."""

    def __init__(self, threads: Callable[[], int], chunk_rows: int | None = None) -> None:
        self.threads = threads
        self.rows = ChunkExtract(threads, chunk_rows)
        self._planes_for: np.ndarray | None = None  # the view matrix the planes were made with
        self._planes = np.zeros((0, 4))
        self._view: tuple[CameraMatrices, bytes, np.ndarray] | None = None
        # the methods callers name (a name each frame: one method kept per name, so temporal
        # culling keeps its rows' state); a caller's own CullingMethod is used as given
        self.methods: dict[str, CullingMethod] = {}  # (by Culling: a str)
        self._kinds = light_kinds()  # which light kinds the world has: absent ones cost no query
        self._point_lights: KeptPoints = {}  # per table: views kept
        self.casters = ShadowExtract()
        self._default_materials: Materials | None = None  # a world without Materials, when none is given

    def method(self, culling: str | bool | Culling | CullingMethod) -> CullingMethod:
        """The method `culling` is or names (culling.culling_name: UsageError for an unknown one)."""
        if isinstance(culling, CullingMethod):
            return culling
        kept = self.methods.get(culling) if isinstance(culling, str) else None
        if kept is None:
            name = culling_name(culling)
            kept = self.methods.get(name)
            if kept is None:
                kept = self.methods[name] = METHODS[name]()
        return kept

    @property
    def temporal(self) -> TemporalCuller:
        """Temporal culling's state, of the method the name `temporal` picks here (tests, benches)."""
        method = self.method(Culling.TEMPORAL)
        assert isinstance(method, TemporalCulling)
        return method.culler

    @property
    def chunk_rows(self) -> int | None:
        return self.rows.chunk_rows

    @chunk_rows.setter
    def chunk_rows(self, rows: int | None) -> None:
        self.rows.chunk_rows = rows

    def extract(
        self,
        world: World,
        aspect: float,
        mesh_count: int,
        culling: str | bool | Culling | CullingMethod,
        material_count: int = 1 << 32,
        set_aside: np.ndarray | None = None,
        region: tuple[float, float, float, float] | None = None,
        dt: float | None = None,
        bounds: Any = None,
        materials: Materials | None = None,
        camera: CameraMatrices | None = None,
        layers: int | None = None,
    ) -> FrameData:
        """`culling`: a CullingMethod, or its name (CULLING; a bool: frustum or none);
        `set_aside`: per material, whether its rows are drawn apart (Materials.set_aside);
        `region`: the part of the target the view shows in (camera_matrices), culled to it;
        temporal culling needs `dt` (the seconds since the last frame) and `bounds` (the mesh
        registry's); `materials`: the world's as the caller found them (Renderer.materials),
        else extracted here. `camera` and `layers`: one view's camera (extract/views.py: a split
        screen's, a render texture's) and the layers it draws, instead of the window camera's."""
        method = self.method(culling)
        cam = camera_matrices(world, aspect, region) if camera is None else camera
        origin = render_origin(world)
        origin_key = origin.tobytes()
        view = self.view(cam, origin, origin_key)
        positional, directional = extract_lights(world, self._kinds, self._point_lights)
        skins = extract_deform(world, origin) if structural(world, "deformed", deformed) else None
        chunks = self.rows.chunks(world, mesh_count, material_count, skins)
        aside = None
        layers = camera_layers(world) if layers is None else layers
        if chunks and (set_aside is not None or self.rows.hides_rows(world, layers)):
            chunks, seen_aside = self.rows.split(world, chunks, set_aside, layers, skins)
            aside = seen_aside if set_aside is not None else None
        planes = method.planes(lambda: self.planes(cam.lens, view))
        masks = method.masks(world, cam, origin, planes, dt, bounds)  # (temporal culling's: it reads the world)
        if materials is None:
            if self._default_materials is None:
                self._default_materials = Materials()
            materials = extract_materials(world, self._default_materials)
        return FrameData(
            camera=cam,
            origin=origin,
            origin_key=origin_key,
            view=view,
            culling=method,
            planes=planes,
            lights=positional,
            directional=directional,
            light_count=sum(map(len, positional)) + sum(map(len, directional)),
            chunks=chunks,
            candidates=sum(len(c.handle) for c in chunks),
            set_aside=aside,
            masks=masks,
            shadows=self.casters(world),
            environment=extract_environment(world),
            materials=materials,
            deform=None if skins is None else skins.rows,
        )

    def view(self, cam: CameraMatrices, origin: np.ndarray, origin_key: bytes) -> np.ndarray:
        """view_from_origin, kept while the camera matrices and the origin stay the same (a new
        array whenever they change: `planes` keys on its identity)."""
        cached = self._view
        if cached is None or cached[0] is not cam or cached[1] != origin_key:
            cached = self._view = (cam, origin_key, view_from_origin(cam, origin))
        return cached[2]

    def planes(self, projection: np.ndarray, view: np.ndarray) -> np.ndarray:
        if view is not self._planes_for:
            self._planes_for, self._planes = view, frustum_planes(projection, view)
        return self._planes

    # the extract functions under the names older code calls (tests, benches)
    @staticmethod
    def lights(
        world: World, kinds: LightKinds | None = None, kept: KeptPoints | None = None
    ) -> tuple[list[PositionalLights], list[DirectionalLights]]:
        return extract_lights(world, kinds, kept)

    def chunks(self, world: World, mesh_count: int, material_count: int = 1 << 32) -> list[Chunk]:
        return self.rows.chunks(world, mesh_count, material_count)

    def split(self, world: World, chunks: list[Chunk], blend: np.ndarray) -> tuple[list[Chunk], SetAsideRows]:
        return self.rows.split(world, chunks, blend)

    def rows_per_job(self, rows: int) -> int:
        return self.rows.rows_per_job(rows)


def camera_layers(world: World) -> int:
    """The layers the window's camera draws (its RenderLayers' mask; layer 0 without one)."""
    if not structural(world, "render_layers", _has_layers):  # the usual world: no layers at all
        return DEFAULT_LAYERS
    eid = active_camera(world)
    return int(world.get(eid, RenderLayers).mask) if world.has(eid, RenderLayers) else DEFAULT_LAYERS


def _has_layers(world: World) -> bool:
    return bool(world.query(RenderLayers, write=()).count())
