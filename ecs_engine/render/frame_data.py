"""Frame extraction: the world turned into the plain arrays one frame draws (camera, render
origin, view, frustum planes, lights, chunks of mesh rows), with no GPU in sight.

The renderer records from a `FrameData` only, so what a frame will draw can be tested without a
device, and the world is read in one place. Everything here is kept between frames while its
inputs are unchanged: a still scene of 100 cubes has a CPU budget of 250 us a frame, and
rebuilding matrices, planes and chunk lists would spend a good part of it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..components import (
    DirectionalLight,
    Mesh,
    ModelMatrix,
    NotShadowCaster,
    NotShadowReceiver,
    PointLight,
    SpotLight,
    Transform,
    render_origin,
)
from ..ecs.schedule import any_with
from ..ecs.world import World
from ..jobs import row_chunks
from ..maths.culling import frustum_planes
from .camera import CameraMatrices, camera_matrices, view_from_origin
from .config import Culling, RenderConfig, check, choice
from .light_rows import DirectionalLights, PositionalLights, local_minus_z, spot_cones
from .temporal_culling import TemporalCulling

_HANDLE = (Mesh, "handle")  # the columns whose writes make the extractor check handles again
_MATERIAL = (Mesh, "material")
MODEL_COLUMN = (ModelMatrix, "model")  # a Chunk's `ticks` key: when its model matrices were last written
# Rows per job, by default about one job per thread but never under MIN_CHUNK_ROWS. Measured on
# the H100 host (native recorder): 4,096-row jobs were slower on 16 threads than on 4 (per-job
# Python under GIL contention); at 1M entities and 16 threads the instanced CPU frame took
# 21.49 ms with 16,384-row jobs, 17.98 ms with 32,768 and 14.06 ms with 65,536 (one per core);
# but fixed 65,536-row jobs leave 100k entities in two jobs, so the size follows the thread count.
MIN_CHUNK_ROWS = 16_384


NOT_CASTER, NOT_RECEIVER = 1, 2
# per frame; only when due (temporal_culling.py); the frustum, then what is hidden (the indirect
# mode: render/occlusion.py); off
CULLING = Culling.names()


def check_culling(culling: str | bool, mode: str | None = "instanced") -> str:
    """The culling method named (True: frustum, False: none); UsageError for an unknown one, or
    (unless `mode` is None) one that `mode` cannot cull with (config.RULES: temporal is the CPU
    modes', occlusion the indirect mode's)."""
    name = ("frustum" if culling else "none") if isinstance(culling, bool) else culling
    if mode is None and name in CULLING:
        return str(name)  # extract's call each frame: the name alone, without building a config
    if mode is None:
        return str(choice("culling", name).value)
    return str(check(RenderConfig.from_strings(culling=name, mode=mode), only=("culling",)).culling.value)


def shadow_flags(batch: Any) -> int:
    """A table's shadow tags as Chunk.flags: a tag is in every row of a table or in none."""
    types = batch.table.type_set
    return (NOT_CASTER if NotShadowCaster in types else 0) | (NOT_RECEIVER if NotShadowReceiver in types else 0)


@dataclass
class Chunk:
    """A run of rows of one table: one job. Views into the world's columns."""

    model: np.ndarray
    handle: np.ndarray
    material: np.ndarray
    offset: int  # first row of this chunk's slice of the instance buffer
    flags: int = 0  # NOT_CASTER, NOT_RECEIVER: its table's shadow tags (components/shadow.py)
    table: int = -1  # the table's id and the chunk's first row in it (FrameData.masks)
    start: int = 0
    # its table's column ticks, for views of the table's own columns (not gathered copies): what
    # a frame slot's rows were written from can then be told unchanged (chunk_paths.py)
    ticks: dict[Any, int] | None = None

    @property
    def name(self) -> str:
        return f"rows {self.offset}:{self.offset + len(self.handle)}"


@dataclass
class SetAsideRows:
    """This frame's rows drawn apart from the chunks (set_aside_pass.py): those whose material is
    alpha-blended (after the opaque ones, back to front) or has its own fill (wireframe, points)."""

    model: np.ndarray
    handle: np.ndarray
    material: np.ndarray
    # the same rows as shadow casters, per table (its shadow tags), offsets after the chunks' rows
    casters: list[Chunk] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.handle)


@dataclass
class FrameData:
    camera: CameraMatrices
    origin: np.ndarray  # float64: model matrices are relative to it
    origin_key: bytes
    view: np.ndarray  # float32 (4, 4): the camera's view for matrices relative to `origin`
    planes: np.ndarray | None  # frustum planes (k, 4) float64, or None: culling off
    lights: list[PositionalLights]  # per table of point or spot lights
    directional: list[DirectionalLights]
    light_count: int  # of every kind
    chunks: list[Chunk]
    candidates: int  # rows with a mesh in the chunks (opaque and masked materials), before culling
    set_aside: SetAsideRows | None = None  # None: no material is blended or has its own fill
    masks: dict[int, np.ndarray] | None = None  # temporal culling: per table id, the rows to draw

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
    """Turns a world into `FrameData`. A table's rows are cut into jobs of `chunk_rows`, or
    by default into about one job per thread of `threads()` (at least MIN_CHUNK_ROWS rows)."""

    def __init__(self, threads: Callable[[], int], chunk_rows: int | None = None) -> None:
        self.threads = threads
        self.chunk_rows = chunk_rows
        self._planes_for: np.ndarray | None = None  # the view matrix the planes were made with
        self._planes = np.zeros((0, 4))
        self._view: tuple[CameraMatrices, bytes, np.ndarray] | None = None
        self._chunks_key: tuple[object, ...] = ()
        self._chunks: list[Chunk] = []
        self._split_key: tuple[object, ...] = ()
        self._split: list[tuple[np.ndarray, np.ndarray]] = []  # per table: chunk rows, rows set aside
        self.temporal = TemporalCulling()
        # which light kinds the world has (kept while its structure stays): absent ones cost no query
        self._kinds = (
            any_with(PointLight, Transform),
            any_with(SpotLight, Transform),
            any_with(DirectionalLight, Transform),
        )
        self._point_lights: dict[int, tuple[Any, int, int, PositionalLights]] = {}  # per table: views kept

    def extract(
        self,
        world: World,
        aspect: float,
        mesh_count: int,
        culling: str | bool,
        material_count: int = 1 << 32,
        set_aside: np.ndarray | None = None,
        region: tuple[float, float, float, float] | None = None,
        dt: float | None = None,
        bounds: Any = None,
    ) -> FrameData:
        """`culling`: CULLING (a bool: frustum or none); `set_aside`: per material, whether its
        rows are drawn apart (Materials.set_aside); `region`: the part of the target the view
        shows in (camera_matrices), culled to it; temporal culling needs `dt` (the seconds since
        the last frame) and `bounds` (the mesh registry's)."""
        culling = check_culling(culling, None)
        cam = camera_matrices(world, aspect, region)
        origin = render_origin(world)
        origin_key = origin.tobytes()
        view = self.view(cam, origin, origin_key)
        positional, directional = self.lights(world, self._kinds, self._point_lights)
        chunks = self.chunks(world, mesh_count, material_count)
        aside = None
        if set_aside is not None and chunks:
            chunks, aside = self.split(world, chunks, set_aside)
        planes = self.planes(cam.lens, view) if culling != "none" else None
        masks = None
        if culling == "temporal" and planes is not None:
            masks = self.temporal.masks(world, cam, origin, planes, dt, bounds)
        return FrameData(
            camera=cam,
            origin=origin,
            origin_key=origin_key,
            view=view,
            planes=planes,
            lights=positional,
            directional=directional,
            light_count=sum(map(len, positional)) + sum(map(len, directional)),
            chunks=chunks,
            candidates=sum(len(c.handle) for c in chunks),
            set_aside=aside,
            masks=masks,
        )

    def split(self, world: World, chunks: list[Chunk], blend: np.ndarray) -> tuple[list[Chunk], SetAsideRows]:
        """The chunks without the rows set aside (gathered copies, made each frame: the model
        matrices change), and those rows. Which rows those are is kept while the tables, their
        materials and the flags stay the same."""
        query = world.query(ModelMatrix, Mesh, write=())
        key = (
            world,
            blend.tobytes(),
            *[(t.id, t.version, t.count, t.column_ticks[_MATERIAL]) for t in query.tables],
        )
        if key != self._split_key:
            self._split = []
            for batch in query:
                flags = blend[batch[Mesh].material]
                self._split.append((np.flatnonzero(~flags), np.flatnonzero(flags)))
            self._split_key = key
        opaque: list[Chunk] = []
        models, handles, materials, flags = [], [], [], []
        offset = 0
        for batch, (keep, blended) in zip(query, self._split):
            m, mesh = batch[ModelMatrix], batch[Mesh]
            model, handle, material = m.model[keep], mesh.handle[keep], mesh.material[keep]
            for s in row_chunks(len(keep), self.rows_per_job(len(keep))):
                opaque.append(Chunk(model[s], handle[s], material[s], offset, shadow_flags(batch)))
                offset += s.stop - s.start
            models.append(m.model[blended])
            handles.append(mesh.handle[blended])
            materials.append(mesh.material[blended])
            flags.append(shadow_flags(batch))
        rows = SetAsideRows(np.concatenate(models), np.concatenate(handles), np.concatenate(materials))
        for model, handle, material, tags in zip(models, handles, materials, flags, strict=True):
            if len(handle):  # a shadow view's rows: the chunks', then these
                rows.casters.append(Chunk(model, handle, material, offset, tags))
                offset += len(handle)
        return opaque, rows

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

    @staticmethod
    def lights(
        world: World,
        kinds: tuple[Callable[[World], bool], ...] | None = None,
        kept: dict[int, tuple[Any, int, int, PositionalLights]] | None = None,
    ) -> tuple[list[PositionalLights], list[DirectionalLights]]:
        """Per table: point lights (views of their columns), spot lights (with the direction each
        shines, from its rotation, and its cone) and directional lights (see light_rows.py).
        `kinds`: whether the world has each (point, spot, directional; run conditions); `kept`:
        a table's point lights, kept while it keeps its layout and rows (views see new values)."""
        points, spots, suns = kinds or (lambda w: True,) * 3
        kept = {} if kept is None else kept
        positional = []
        for batch in world.query(PointLight, Transform, write=()) if points(world) else ():
            table = batch.table
            found = kept.get(table.id)
            if found is None or found[0] is not table or found[1] != table.version or found[2] != len(batch):
                light = batch[PointLight]
                made = PositionalLights(
                    batch[Transform].position, light.radius, light.color, light.intensity, entity=batch.entities
                )
                found = kept[table.id] = (table, table.version, len(batch), made)
            positional.append(found[3])
        for batch in world.query(SpotLight, Transform, write=()) if spots(world) else ():
            spot, transform = batch[SpotLight], batch[Transform]
            positional.append(
                PositionalLights(
                    transform.position,
                    spot.radius,
                    spot.color,
                    spot.intensity,
                    local_minus_z(transform.rotation),
                    spot_cones(spot.inner_angle, spot.outer_angle),
                    batch.entities,
                )
            )
        directional = []
        for batch in world.query(DirectionalLight, Transform, write=()) if suns(world) else ():
            sun = batch[DirectionalLight]
            directional.append(
                DirectionalLights(local_minus_z(batch[Transform].rotation), sun.color, sun.illuminance, batch.entities)
            )
        return positional, directional

    def chunks(self, world: World, mesh_count: int, material_count: int = 1 << 32) -> list[Chunk]:
        """Row ranges of every table with a ModelMatrix and a Mesh, each with its buffer slice.
        Kept while the world is the same and its tables keep their rows, layout and Mesh
        columns (the views stay valid and see every value written since)."""
        query = world.query(ModelMatrix, Mesh, write=())
        tables = query.tables
        key = (
            world,
            mesh_count,
            material_count,
            self.chunk_rows,
            self.threads(),
            *[(t.id, t.version, t.count, t.column_ticks[_HANDLE], t.column_ticks[_MATERIAL]) for t in tables],
        )
        if key == self._chunks_key:
            return self._chunks
        out: list[Chunk] = []
        offset = 0
        for batch in query:
            m, mesh = batch[ModelMatrix], batch[Mesh]
            for s in row_chunks(len(batch), self.rows_per_job(len(batch))):
                flags, table = shadow_flags(batch), batch.table.id
                ticks = batch.table.column_ticks
                out.append(Chunk(m.model[s], mesh.handle[s], mesh.material[s], offset, flags, table, s.start, ticks))
                offset += s.stop - s.start
        if out:
            top = max(int(c.handle.max()) for c in out)
            if top >= mesh_count:
                raise ValueError(f"Mesh.handle {top} does not name an uploaded mesh ({mesh_count} uploaded)")
            top = max(int(c.material.max()) for c in out)
            if top >= material_count:
                raise ValueError(
                    f"Mesh.material {top} does not name a material (the world has {material_count}: "
                    "add materials with ecs_engine.render.materials.materials(world).add)"
                )
        self._chunks_key, self._chunks = key, out
        return out

    def rows_per_job(self, rows: int) -> int:
        if self.chunk_rows is not None:
            return self.chunk_rows
        return max(MIN_CHUNK_ROWS, -(-rows // self.threads()))
