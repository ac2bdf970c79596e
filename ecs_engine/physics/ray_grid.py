"""Rays against the bodies' primitive shapes (boxes, spheres, capsules, cylinders), cast by the
engine in compiled loops that release the GIL, over a uniform grid of the shapes' bounds.

Why not the library's batch: culverin's reads each hit's body through Jolt's locking body
interface, so its threads contend: 10,000 rays on a pile of 10,000 boxes took it 3.9-4.4 ms on
16 threads of the GPU host, these 0.73-0.78 (median steps; docs/physics.md). The primitives'
poses are in the library's shared buffers already. A grid of their bounds, a little wide, is
made from them and brought up to each step: the shapes that moved further than that margin are
moved into other cells (ray_refresh.py). Each ray walks it cell by cell (ray_walk.py), testing a
shape's bounds and then its exact shape (ray_shapes.py), as the library does, in float64, on
numba's threads for many rays, the refresh in the same kernel (ray_spread.py). Shapes too big
for the grid's cells (a floor) are tested by every ray."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import native
from ..components.physics import BOX, CAPSULE, SPHERE
from .poses import copy_poses
from .ray_bounds import BLOCK, bounds_of, count_cells, place_cells, starts_of
from .ray_refresh import SPILL, counters, refresh
from .ray_spread import refresh_and_spread
from .ray_walk import cast_rays, claims

CELL_REACH = 0.7  # the grid's cell, in the median shape's reach (its bounding sphere's diameter)
MARGIN = 0.05  # the shapes' bounds in the grid are this many cells wider all round: a shape
# stays in its cells until it moves further than that (ray_refresh.py). In a settling pile of
# 10,000 boxes, 160 shapes a step moved past 0.02 and 20 past 0.05, for 9% more bounds tests a
# ray; 0.1 took 70% more
ROOM = 1  # cells all round the shapes for them to move into before they are spilt (ray_refresh.py)
LARGE_CELLS = 64  # a shape over more cells than this is tested by every ray instead
CELLS_PER_SHAPE = 4  # the grid has at most this many cells per shape (more for far-apart shapes)
SHARED_BUILD = 20_000  # shapes from which the grid is made on the pool's threads
AVAILABLE = cast_rays is not None
_NOTHING = np.empty(0, np.intp)  # no shape to look at


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two views are of the same memory (the library's buffers, viewed again)."""
    return a.shape == b.shape and a.__array_interface__["data"][0] == b.__array_interface__["data"][0]


@dataclass(frozen=True)
class Shapes:
    """The primitive shapes of a world's bodies, as long as no body is made or destroyed:
    `entity` per shape, the `rows` of their bodies in the library's buffers, their kinds and
    Collider sizes; the grid's `cell`, CELL_REACH times the median shape's reach (the diameter
    of its bounding sphere: the same however the shape turns), and which shapes are `big` (over
    LARGE_CELLS cells: tested by every ray), `small` (in the grid) and `large`."""

    entity: np.ndarray
    rows: np.ndarray
    shape: np.ndarray
    size: np.ndarray
    cell: float
    radius: np.ndarray
    big: np.ndarray
    small: np.ndarray
    large: np.ndarray
    watched: np.ndarray

    @classmethod
    def of(cls, entity: np.ndarray, rows: np.ndarray, shape: np.ndarray, size: np.ndarray, still: np.ndarray) -> Shapes:
        shape, size = np.ascontiguousarray(shape, np.int64), np.ascontiguousarray(size, np.float64)
        r, h = size[:, 0], size[:, 1]
        reach = 2.0 * np.select(
            [shape == BOX, shape == SPHERE, shape == CAPSULE],
            [np.linalg.norm(size, axis=1), r, r + h],
            np.hypot(r, h),
        )
        cell = CELL_REACH * float(np.median(reach)) if len(reach) else 1.0
        big = (reach / cell + 1.0) ** 3 > LARGE_CELLS
        rows = np.ascontiguousarray(rows, np.int64)
        small, large, watched = np.flatnonzero(~big), np.flatnonzero(big), np.flatnonzero(~big & ~still)
        return cls(entity, rows, shape, size, cell, reach / 2.0, big, small, large, watched)


@dataclass(frozen=True)
class RayGrid:
    """The shapes and a grid of their bounds: the library's buffers they are posed by
    (`positions`, `rotations`); per shape, its `centre` and `turn` (a unit rotation) when it
    was put in its cells and its `bounds` then, `margin` wider than the shape all round; the
    grid from `origin` in cubes of `cell`, `dims` of them (a cell more all round than the
    shapes needed, for them to move into), whose shapes are items[starts[c]:starts[c] +
    fill[c]] for cell c = (z * ny + y) * nx + x, their bounds boxes[...] beside them (low,
    then high), room to spare up to starts[c + 1]. `refresh` moves the shapes that left their
    bounds into other cells: the grid's arrays change in place (PhysicsWorld.ray_lock)."""

    shapes: Shapes
    positions: np.ndarray
    rotations: np.ndarray
    centre: np.ndarray
    turn: np.ndarray
    bounds: np.ndarray
    margin: float
    origin: np.ndarray
    cell: float
    dims: np.ndarray
    starts: np.ndarray
    fill: np.ndarray
    items: np.ndarray
    boxes: np.ndarray
    marks: np.ndarray  # per shape, 1 while a refresh has it down as escaped
    spill: np.ndarray  # how many shapes are outside the grid's cells, then they (ray_refresh.SPILL)

    @classmethod
    def build(cls, shapes: Shapes, positions: np.ndarray, rotations: np.ndarray, pool: Any = None) -> RayGrid:
        """The grid of `shapes` where their bodies are now (the library's buffers: positions
        (M, 4) float64, rotations (M, 4) float32): on `pool`'s threads for SHARED_BUILD shapes
        or more (they take blocks of shapes from shared counters, three maps), else on this
        one (waking the threads costs more than the work saves: 0.2-0.4 ms a map on the GPU
        host). Where the shapes lie so far apart that more than CELLS_PER_SHAPE cells a shape
        would be needed, the cells are larger."""
        assert bounds_of is not None and count_cells is not None and place_cells is not None and starts_of is not None
        count, small = len(shapes.entity), shapes.small
        jobs = 1 if pool is None or count < SHARED_BUILD else min(pool.threads, -(-count // BLOCK))
        shared = np.zeros(3, np.int64)

        def run(kernel: Any, *args: Any) -> None:
            if jobs == 1:
                kernel(shared, BLOCK, *args)
            else:
                pool.map(lambda _: kernel(shared, BLOCK, *args), range(jobs))

        bounds, parts = np.empty((count, 6)), np.empty((-(-count // BLOCK), 2, 3))
        margin = MARGIN * shapes.cell
        run(bounds_of, positions, rotations, shapes.rows, shapes.shape, shapes.size, shapes.big, margin, bounds, parts)
        low, high = (parts[:, 0].min(axis=0), parts[:, 1].max(axis=0)) if len(small) else (np.zeros(3), np.ones(3))
        cell = shapes.cell
        dims = np.maximum(np.ceil((high - low) / cell), 1.0) + 2 * ROOM
        most = CELLS_PER_SHAPE * len(small) + 64
        if dims.prod() > most:
            cell *= float((dims.prod() / most) ** (1 / 3))
            dims = np.maximum(np.ceil((high - low) / cell), 1.0) + 2 * ROOM
        low, dims, cell = low - ROOM * cell, dims.astype(np.int64), float(cell)
        fill = np.zeros(int(dims.prod()), np.int64)
        run(count_cells, bounds, small, low, cell, dims, fill, jobs > 1)
        starts = starts_of(fill)
        items, boxes = np.empty(starts[-1], np.int32), np.empty((starts[-1], 6), np.float32)
        run(place_cells, bounds, small, (low, cell, dims, starts, fill, items, boxes), jobs > 1)
        centre, turn = np.empty((count, 3)), np.empty((count, 4))
        copy_poses(positions, rotations, shapes.rows, np.arange(count), centre, turn)
        marks, spill = np.zeros(count, np.uint8), np.zeros(SPILL + 1, np.int64)
        poses = (positions, rotations, centre, turn, bounds, margin)
        return cls(shapes, *poses, low, cell, dims, starts, fill, items, boxes, marks, spill)

    @property
    def layout(self) -> tuple:
        """(origin, cell, dims, starts, fill, items, boxes): the grid as its kernels take it."""
        return self.origin, self.cell, self.dims, self.starts, self.fill, self.items, self.boxes

    def serves(self, shapes: Shapes, positions: np.ndarray, rotations: np.ndarray) -> bool:
        """Whether this grid was made for these `shapes`, posed by these buffers (whether they
        still lie within their bounds is `refresh`'s to see to)."""
        return shapes is self.shapes and _same(positions, self.positions) and _same(rotations, self.rotations)

    def refresh(self, everything: bool = True) -> bool:
        """Bring the grid up to the buffers' poses (ray_refresh.py): every shape that moved
        further than the margin since it was put in its cells moved into the cells it covers
        now; with `everything` False only the watched shapes are looked at (no body was put
        anywhere since the last refresh: a static one has not moved). False where the grid must
        be made again instead (more than SPILL shapes found no room in the cells or left the
        grid's box)."""
        assert refresh is not None
        s = self.shapes
        return refresh(counters(), *self._refresh(s.small if everything else s.watched))

    def refresh_and_cast(
        self,
        everything: bool,
        jobs: int,
        origins: np.ndarray,
        directions: np.ndarray,
        max_distance: float,
        out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        shared: np.ndarray,
        answer: np.ndarray,
    ) -> bool:
        """`refresh`, then `cast`, in one kernel on `jobs` of numba's threads (ray_spread.py):
        False where the grid must be made again (then no ray is cast: shared[0] is 0)."""
        s = self.shapes
        rays = self._rays(origins, directions, max_distance, shared, answer, out)
        return self._spread(s.small if everything else s.watched, jobs, rays)

    def _spread(self, looked: np.ndarray, jobs: int, rays: tuple) -> bool:
        """ray_spread's kernel: the `looked` shapes' refresh and the rays, on `jobs` threads."""
        assert refresh_and_spread is not None
        with native.LAUNCH:
            return bool(refresh_and_spread(native.spread(jobs), counters(), self._refresh(looked)[0], *rays))

    def _refresh(self, looked: np.ndarray) -> tuple[tuple, tuple]:
        """The refresh's arguments: ray_refresh.look's (the shapes to look at), settle's."""
        s = self.shapes
        poses, since = (self.positions, self.rotations, s.rows), (self.margin, self.centre, self.turn)
        look = (*poses, looked, s.radius, *since, self.marks)
        return look, (*poses, s.shape, s.size, *since, self.bounds, self.layout, self.spill)

    def _rays(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        max_distance: float,
        shared: np.ndarray | None,
        answer: np.ndarray | None,
        out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    ) -> tuple:
        """cast_rays' arguments."""
        s = self.shapes
        shared = claims() if shared is None else shared
        answer = np.arange(len(s.shape)) if answer is None else answer
        shapes = (self.positions, self.rotations, s.rows, s.shape, s.size, s.large)
        return (origins, directions, float(max_distance), shared, *shapes, *self._walk, answer, *out)

    def cast(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        max_distance: float,
        out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        shared: np.ndarray | None = None,
        answer: np.ndarray | None = None,
        jobs: int = 1,
    ) -> None:
        """Cast the rays (origins and directions, float64, C order) into `out`: per ray,
        answer[the shape it hits first] (by default the shape's index into shapes.entity; -1:
        none, -2: a ray that is not finite or has no direction), the distance, the point and
        the normal. `jobs` over 1: on that many of numba's threads at once (ray_spread.py).
        `shared`: claims() that threads casting the same rays share them by (this one casts
        those left, RAY_BLOCK at a time); without, this call casts them all."""
        assert cast_rays is not None
        rays = self._rays(origins, directions, max_distance, shared, answer, out)
        if jobs > 1 and refresh_and_spread is not None:
            self._spread(_NOTHING, jobs, rays)  # (no shape looked at: the rays alone)
        else:
            cast_rays(*rays)

    @property
    def _walk(self) -> tuple:
        """(layout, bounds, spill): the grid as the walk takes it."""
        return self.layout, self.bounds, self.spill
