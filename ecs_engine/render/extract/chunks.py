"""Extract: the rows with a mesh, as chunks of one table's rows (one job each) with their slices
of the instance buffer, and the rows set aside (drawn apart: blended materials, fills of their
own). Reads the ModelMatrix, Mesh and RenderLayers columns and the shadow tags' presence only.

A camera draws the rows whose RenderLayers share a bit with its own (components/camera_views.py;
rows without the component are on layer 0). While every row is seen, chunks are views; rows left
out are gathered into copies each frame, as the rows set aside are.

Chunks are views into the world's columns: a frame's jobs read the values written since (the
frame is extracted after the systems ran and drawn before they run again). They are kept while
the tables keep their rows, layout and Mesh columns: rebuilding them would spend a good part of
a still scene's CPU budget (250 us a frame for 100 cubes).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...components import Mesh, ModelMatrix, NotShadowCaster, NotShadowReceiver
from ...components.animation import Skinned
from ...components.camera import RenderLayers
from ...components.camera_views import DEFAULT_LAYERS
from ...ecs.structural import structural
from ...ecs.world import World
from ...jobs import row_chunks
from .skins import DeformFrame

# what a system running ChunkExtract declares
READS = (ModelMatrix, Mesh, NotShadowCaster, NotShadowReceiver, RenderLayers, Skinned)
_HANDLE = (Mesh, "handle")  # the columns whose writes make the extractor check handles again
_MATERIAL = (Mesh, "material")
_LAYERS = (RenderLayers, "mask")
_SKIN, _COPY = (Skinned, "skin"), (Skinned, "copy")
MODEL_COLUMN = (ModelMatrix, "model")  # a Chunk's `ticks` key: when its model matrices were last written
# Rows per job, by default about one job per thread but never under MIN_CHUNK_ROWS. Measured on
# the H100 host (native recorder): 4,096-row jobs were slower on 16 threads than on 4 (per-job
# Python under GIL contention); at 1M entities and 16 threads the instanced CPU frame took
# 21.49 ms with 16,384-row jobs, 17.98 ms with 32,768 and 14.06 ms with 65,536 (one per core);
# but fixed 65,536-row jobs leave 100k entities in two jobs, so the size follows the thread count.
MIN_CHUNK_ROWS = 16_384

NOT_CASTER, NOT_RECEIVER = 1, 2


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
    # per row, the bits a skinned or morphed row adds to its Instance's misc.z and misc.w (z | w << 32:
    # where its joints and morph weights are, extract/skins.py), or None
    extra: np.ndarray | None = None

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
    extra: np.ndarray | None = None  # per row, its misc bits (Chunk.extra); None: no row is skinned or morphed
    # the same rows as shadow casters, per table (its shadow tags), offsets after the chunks' rows
    casters: list[Chunk] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.handle)


class ChunkExtract:
    """The chunks of a world's rows with a mesh. A table's rows are cut into jobs of
    `chunk_rows`, or by default into about one job per thread of `threads()` (at least
    MIN_CHUNK_ROWS rows)."""

    def __init__(self, threads: Callable[[], int], chunk_rows: int | None = None) -> None:
        self.threads = threads
        self.chunk_rows = chunk_rows
        self._chunks_key: tuple[object, ...] = ()
        self._chunks: list[Chunk] = []
        self._split_key: tuple[object, ...] = ()
        self._split: list[tuple[np.ndarray, np.ndarray]] = []  # per table: chunk rows, rows set aside

    def chunks(
        self, world: World, mesh_count: int, material_count: int = 1 << 32, skins: DeformFrame | None = None
    ) -> list[Chunk]:
        """Row ranges of every table with a ModelMatrix and a Mesh, each with its buffer slice
        (and its skinned rows' misc.w from `skins`). Kept while the world is the same and its
        tables keep their rows, layout, Mesh and Skinned columns (the views stay valid and see
        every value written since)."""
        query = world.query(ModelMatrix, Mesh, write=())
        tables = query.tables
        key = (
            world,
            mesh_count,
            material_count,
            self.chunk_rows,
            self.threads(),
            None if skins is None else skins.key,
            *[(t.id, t.version, t.count, t.column_ticks[_HANDLE], t.column_ticks[_MATERIAL]) for t in tables],
        )
        if skins is not None:  # the rows' skins name their chunks' extra (weights: read each frame)
            key += tuple((t.column_ticks.get(_SKIN), t.column_ticks.get(_COPY)) for t in tables)
        if key == self._chunks_key:
            return self._chunks
        out: list[Chunk] = []
        offset = 0
        for batch in query:
            m, mesh = batch[ModelMatrix], batch[Mesh]
            skin = None if skins is None else skins.row_extra(batch.table, len(batch))
            for s in row_chunks(len(batch), self.rows_per_job(len(batch))):
                flags, table = shadow_flags(batch), batch.table.id
                ticks = batch.table.column_ticks
                chunk = Chunk(m.model[s], mesh.handle[s], mesh.material[s], offset, flags, table, s.start, ticks)
                chunk.extra = None if skin is None else skin[s]
                out.append(chunk)
                offset += s.stop - s.start
        if out:
            top = max(int(c.handle.max()) for c in out)
            if top >= mesh_count:
                raise ValueError(f"Mesh.handle {top} does not name an uploaded mesh ({mesh_count} uploaded)")
            top = max(int(c.material.max()) for c in out)
            if top >= material_count:
                raise ValueError(
                    f"Mesh.material {top} does not name a material (the world has {material_count}: "
                    "add materials with ecs_engine.render.assets.materials.materials(world).add)"
                )
        self._chunks_key, self._chunks = key, out
        return out

    def hides_rows(self, world: World, layers: int) -> bool:
        """Whether a camera seeing `layers` misses some row with a mesh (then `split` keeps
        only the rows it sees)."""
        if not layers & DEFAULT_LAYERS:
            return True
        return structural(world, "layered_meshes", _layered_meshes)  # which tables: only structure changes it

    def split(
        self,
        world: World,
        chunks: list[Chunk],
        blend: np.ndarray | None,
        layers: int = DEFAULT_LAYERS,
        skins: DeformFrame | None = None,
    ) -> tuple[list[Chunk], SetAsideRows]:
        """(Called with the chunks of a world with a mesh.) The chunks without the rows set
        aside (`blend`: per material, or None for none) or outside `layers` (gathered copies,
        made each frame: the model matrices change), and the rows set aside that the camera
        sees. Which rows those are is kept while the tables, their materials and layers,
        `blend` and `layers` stay the same."""
        query = world.query(ModelMatrix, Mesh, write=())
        key = (
            world,
            None if blend is None else blend.tobytes(),
            layers,
            *[(t.id, t.version, t.count, t.column_ticks[_MATERIAL], t.column_ticks.get(_LAYERS)) for t in query.tables],
        )
        if key != self._split_key:
            self._split = []
            for batch in query:
                seen = _seen(batch.table, len(batch), layers)
                flags = np.zeros(len(batch), bool) if blend is None else blend[batch[Mesh].material]
                self._split.append((np.flatnonzero(seen & ~flags), np.flatnonzero(seen & flags)))
            self._split_key = key
        opaque: list[Chunk] = []
        models, handles, materials, flags, skinned = [], [], [], [], []
        offset = 0
        for batch, (keep, blended) in zip(query, self._split):
            m, mesh = batch[ModelMatrix], batch[Mesh]
            model, handle, material = m.model[keep], mesh.handle[keep], mesh.material[keep]
            skin = None if skins is None else skins.row_extra(batch.table, len(batch))
            for s in row_chunks(len(keep), self.rows_per_job(len(keep))):
                chunk = Chunk(model[s], handle[s], material[s], offset, shadow_flags(batch))
                chunk.extra = None if skin is None else skin[keep][s]
                opaque.append(chunk)
                offset += s.stop - s.start
            models.append(m.model[blended])
            handles.append(mesh.handle[blended])
            materials.append(mesh.material[blended])
            flags.append(shadow_flags(batch))
            skinned.append(np.zeros(len(blended), np.uint64) if skin is None else skin[blended])
        rows = SetAsideRows(np.concatenate(models), np.concatenate(handles), np.concatenate(materials))
        rows.extra = np.concatenate(skinned) if skins is not None else None
        for model, handle, material, tags, skin in zip(models, handles, materials, flags, skinned, strict=True):
            if len(handle):  # a shadow view's rows: the chunks', then these
                rows.casters.append(Chunk(model, handle, material, offset, tags, extra=skin if skins else None))
                offset += len(handle)
        return opaque, rows

    def rows_per_job(self, rows: int) -> int:
        if self.chunk_rows is not None:
            return self.chunk_rows
        return max(MIN_CHUNK_ROWS, -(-rows // self.threads()))


def _seen(table: Any, rows: int, layers: int) -> np.ndarray:
    """Per row of `table`, whether a camera seeing `layers` sees it."""
    if not table.has(RenderLayers):
        return np.full(rows, bool(layers & DEFAULT_LAYERS))
    return (table.columns[_LAYERS][:rows] & np.uint32(layers)) != 0


def _layered_meshes(world: World) -> bool:
    """Whether some row with a mesh has RenderLayers."""
    return any(t.has(RenderLayers) and t.count for t in world.query(ModelMatrix, Mesh, write=()).tables)
