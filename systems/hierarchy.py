"""World transforms through the Parent hierarchy, level by level, vectorised.

Each frame (after TransformSystem, which wrote every ModelMatrix as if each entity were a root):
every entity with Parent gets world = parent's world @ own local matrix, parents before children
(a compiled pass per level, its rows cut into chunks on the JobPool, or, for a forest of many
trees such as a crowd's skeletons, a compiled pass per job of whole trees; a batched float64
matmul per level without numba), written
to WorldMatrix, and its ModelMatrix rewritten from it relative to the render origin, in float64
before the cast (so a hierarchy 10^7 units out keeps its precision). A child whose parent is -1
or dead is a root; one whose parent has no Parent uses that parent's Transform as its world. A
loop is an EcsError naming its entities.

The plan (which row is whose parent, the level order, where each outside parent's Transform
lives) is kept while the tables holding Parent, their Parent columns and the tables of those
outside parents are unchanged: a still hierarchy whose transforms move costs only the gathers,
the pass and the writes. Ids are matched through the world's entity index (a scatter and a
gather), never sorted and never looped over in Python.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from ecs_engine import native
from ecs_engine.components import ModelMatrix, RenderOrigin, Transform, render_origin
from ecs_engine.components.hierarchy import Parent, WorldMatrix
from ecs_engine.ecs.entities import INDEX_MASK
from ecs_engine.ecs.errors import EcsError
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.ecs.world import World
from ecs_engine.jobs import JobPool, over_rows
from ecs_engine.maths.decompose import trs_matrices

_PARENT = (Parent, "entity")
# a level's rows per job on the pool: a skinned crowd's levels hold tens of thousands of joints
# each, which whole jobs of jobs.CHUNK_ROWS would leave on one thread. Not fewer: smaller jobs
# were slower on 16 threads (each pays the compiled pass's dispatch of its thirteen arguments, it
# seems)
LEVEL_CHUNK_ROWS = 4096
# with at least this many trees a thread, jobs take whole trees instead: each runs every level of
# its trees in one compiled call, with no wait between levels (a crowd: 10k trees of 25 joints)
TREES_PER_JOB = 4


@dataclass
class _Plan:
    key: tuple[Any, ...]
    tables: list[Any]  # the tables with Parent, in row order (those with Transform first)
    offsets: dict[int, int]  # table id -> its first row
    count: int
    levels: list[np.ndarray]  # the same rows by depth (the NumPy form)
    parent_row: np.ndarray  # per row: its parent's row, -1 where the parent is outside or none
    # per table holding parents outside the hierarchy: (table, its rows, our rows); the rows of a
    # table without Transform are empty (those parents are the identity)
    outside: list[tuple[Any, np.ndarray, np.ndarray]]
    outside_versions: tuple[int, ...]  # those tables' versions when planned
    above_row: np.ndarray  # per row: where its parent outside the hierarchy is in run's `above` (-1: none)
    # per row: its tree (its level-0 ancestor's row) and depth; many trees (a crowd) are cut into
    # jobs of whole trees (_tree_jobs, kept per job count)
    tree: np.ndarray
    depth: np.ndarray
    jobs: dict[int, tuple[np.ndarray, list[int]]]


def levels(parent_row: np.ndarray, kids: np.ndarray) -> list[np.ndarray]:
    """Rows by depth: level 0 those whose parent is no hierarchy row (a root, -1 or dead), then
    their children, and so on. Raises EcsError on a loop."""
    depth = np.where(parent_row < 0, 0, -1)
    known = depth >= 0
    for level in range(1, len(kids) + 1):
        step = ~known & known[np.maximum(parent_row, 0)] & (parent_row >= 0)
        if not step.any():
            break
        depth[step] = level
        known |= step
    if not known.all():
        loop = kids[~known][:6].tolist()
        raise EcsError(f"a parent chain loops through entities {loop}: a hierarchy must end in a root")
    return [np.flatnonzero(depth == d) for d in range(int(depth.max()) + 1)] if len(depth) else []


@native.inner
def _trs(position, rotation, scale, row, m):  # pragma: no cover - compiled
    """m (3, 4) = T R S of `row` (the quaternion normalised)."""
    x, y, z, w = rotation[row, 0], rotation[row, 1], rotation[row, 2], rotation[row, 3]
    inv = 1.0 / np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x * inv, y * inv, z * inv, w * inv
    sx, sy, sz = scale[row, 0], scale[row, 1], scale[row, 2]
    m[0, 0], m[0, 1], m[0, 2] = (1 - 2 * (y * y + z * z)) * sx, 2 * (x * y - z * w) * sy, 2 * (x * z + y * w) * sz
    m[1, 0], m[1, 1], m[1, 2] = 2 * (x * y + z * w) * sx, (1 - 2 * (x * x + z * z)) * sy, 2 * (y * z - x * w) * sz
    m[2, 0], m[2, 1], m[2, 2] = 2 * (x * z - y * w) * sx, 2 * (y * z + x * w) * sy, (1 - 2 * (x * x + y * y)) * sz
    m[0, 3], m[1, 3], m[2, 3] = position[row, 0], position[row, 1], position[row, 2]


@native.njit
def _compose(
    order, parent_row, above_row, trs_a, trs_b, split, above, out_a, model_a, out_b, model_b, origin, drawn_a
):  # pragma: no cover - compiled
    """out[row] = (parent's world) @ T R S(row), rows taken in `order` (parents before children),
    and model[row] = out[row] with `origin` taken from its translation (float32). Rows below
    `split` are the first table's, read from `trs_a` (position, rotation, scale) and written to
    its own columns `out_a` and `model_a` in place (`model_a` only if `drawn_a`: a table of
    joints has no ModelMatrix); the others, less `split`, from `trs_b` into `out_b` and `model_b`
    (the other tables', gathered). `above`: the trs of parents outside the
    hierarchy, the parent of `row` at above_row[row] (-1: none)."""
    above_p, above_r, above_s = above
    pos_a, rot_a, scale_a = trs_a
    pos_b, rot_b, scale_b = trs_b
    m = np.empty((3, 4))
    a = np.empty((3, 4))
    v = np.empty((3, 4))
    for k in range(order.shape[0]):
        row = order[k]
        if row < split:
            _trs(pos_a, rot_a, scale_a, row, m)
        else:
            _trs(pos_b, rot_b, scale_b, row - split, m)
        p = parent_row[row]
        r = above_row[row]
        if p >= 0 and p < split:  # the parent's world matrix, from whichever table holds it
            for i in range(3):
                for j in range(4):
                    a[i, j] = out_a[p, i, j]
        elif p >= 0:
            for i in range(3):
                for j in range(4):
                    a[i, j] = out_b[p - split, i, j]
        elif r >= 0:
            _trs(above_p, above_r, above_s, r, a)
        for i in range(3):
            for j in range(4):
                if p >= 0 or r >= 0:
                    x = a[i, 0] * m[0, j] + a[i, 1] * m[1, j] + a[i, 2] * m[2, j]
                    v[i, j] = x + a[i, 3] if j == 3 else x
                else:
                    v[i, j] = m[i, j]
        if row < split:
            _store(v, origin, out_a, model_a, row, drawn_a)
        else:
            _store(v, origin, out_b, model_b, row - split, True)


@native.inner
def _store(v, origin, out, model, at, drawn):  # pragma: no cover - compiled
    """out[at] = v (3 x 4) over (0, 0, 0, 1); if `drawn`, model[at] the same, its translation
    less `origin`."""
    for i in range(3):
        for j in range(4):
            out[at, i, j] = v[i, j]
    out[at, 3, 0], out[at, 3, 1], out[at, 3, 2], out[at, 3, 3] = 0.0, 0.0, 0.0, 1.0
    if drawn:
        for i in range(3):
            for j in range(4):
                model[at, i, j] = v[i, j] - origin[i] if j == 3 else v[i, j]
        model[at, 3, 0], model[at, 3, 1], model[at, 3, 2], model[at, 3, 3] = 0.0, 0.0, 0.0, 1.0


def _trees(by_level: list[np.ndarray], parent_row: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row: its tree (its level-0 ancestor's row) and its depth."""
    n = len(parent_row)
    tree, depth = np.arange(n), np.zeros(n, np.int64)
    for d, rows in enumerate(by_level[1:], start=1):
        tree[rows] = tree[parent_row[rows]]
        depth[rows] = d
    return tree, depth


def _tree_jobs(plan: _Plan, jobs: int) -> tuple[np.ndarray, list[int]]:
    """The rows in `jobs` runs of whole trees of about equal rows (trees taken by their roots'
    order), each run level by level and in row order within a level, as the level passes read
    the columns (a crowd's joints of one node lie together); and where the runs start."""
    kept = plan.jobs.get(jobs)
    if kept is not None:
        return kept
    n = plan.count
    roots = plan.levels[0]
    sizes = np.bincount(plan.tree, minlength=n)[roots]
    before = np.cumsum(sizes) - sizes  # the rows of the trees before each
    job_of = np.zeros(n, np.int64)
    job_of[roots] = np.minimum(before * jobs // max(n, 1), jobs - 1)
    job = job_of[plan.tree]
    order = np.lexsort((np.arange(n), plan.depth, job))
    cuts = np.searchsorted(job[order], np.arange(jobs + 1)).tolist()
    made = plan.jobs[jobs] = (order, cuts)
    return made


class HierarchySystem(System):
    def __init__(self) -> None:
        reads, writes = [Transform, Parent, RenderOrigin], [WorldMatrix, ModelMatrix]
        super().__init__(reads=reads, writes=writes, name="hierarchy", run_if=any_with(Parent))
        self._plan: _Plan | None = None
        self._world: Any = None
        self._out: tuple[np.ndarray, np.ndarray] | None = None  # see _scratch
        self._gathered: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # see _local

    def plan(self, world: World) -> _Plan | None:
        """The plan for the world as it is (kept while what it depends on is unchanged)."""
        # the largest table first: the native pass writes its columns in place (run)
        with_t = sorted(world.query(Parent, Transform, write=()).tables, key=lambda t: -t.count)
        without_t = world.query(Parent, without=(Transform,), write=()).tables
        tables = [t for t in (*with_t, *without_t) if t.count]
        key = tuple((t.id, t.version, t.column_ticks[_PARENT]) for t in tables)
        old = self._plan
        if old is not None and self._world is world and old.key == key:
            if tuple(t.version for t, _, _ in old.outside) == old.outside_versions:
                return old
        if not tables:
            return None
        offsets, start = {}, 0
        for t in tables:
            offsets[t.id] = start
            start += t.count
        kids = np.concatenate([t.entities[: t.count] for t in tables])
        parent_ids = np.concatenate([t.columns[_PARENT][: t.count] for t in tables])
        live = (parent_ids != -1) & world.alive(parent_ids)
        index = world.storage.index
        slot = np.full(len(index.table), -1, np.int64)  # entity index -> our row
        slot[kids & INDEX_MASK] = np.arange(len(kids))
        at = np.where(live, parent_ids & INDEX_MASK, 0)
        parent_row = np.where(live, slot[at], -1)
        outside_rows = np.flatnonzero(live & (parent_row < 0))
        outside = []
        where = index.table[at[outside_rows]]
        for tid in np.unique(where).tolist():
            table = world.storage.tables[tid]
            mine = outside_rows[where == tid]
            if not table.has(Transform):  # parents without Transform: the identity
                mine = mine[:0]
            outside.append((table, index.row[at[mine]], mine))
        by_level = levels(parent_row, kids)
        versions = tuple(t.version for t, _, _ in outside)
        above_row = np.full(len(kids), -1, np.int64)
        with_rows = [(rows, mine) for _, rows, mine in outside if len(mine)]
        if len(with_rows) == 1:  # run reads that table's columns at the parents' rows
            above_row[with_rows[0][1]] = with_rows[0][0]
        elif with_rows:  # run gathers them in this order
            mine = np.concatenate([m for _, m in with_rows])
            above_row[mine] = np.arange(len(mine))
        tree, depth = _trees(by_level, parent_row)
        plan = _Plan(
            key, tables, offsets, len(kids), by_level, parent_row, outside, versions, above_row, tree, depth, {}
        )
        self._plan, self._world = plan, world
        return plan

    def run(self, world: World, dt: float) -> None:
        plan = self.plan(world)
        if plan is None:
            return
        n, tables = plan.count, plan.tables
        above = self._above(plan)
        origin = np.asarray(render_origin(world), np.float64)
        if native.AVAILABLE:
            self._run_native(world, plan, above, origin)
            return
        trs = self._local(plan)
        # one table (the usual case): the pass writes its columns in place; else into scratch
        # arrays copied out per table
        worlds: list[np.ndarray] = [b[WorldMatrix].matrix for b in world.query(WorldMatrix, with_=(Parent,))]
        models: list[np.ndarray] = [b[ModelMatrix].model for b in world.query(ModelMatrix, with_=(Parent,))]
        direct = len(tables) == 1 and len(worlds) == 1 and len(models) == 1
        out, model = (worlds[0], models[0]) if direct else self._scratch(n)
        self._compose_numpy(plan, trs, above, out)
        model[:] = out
        model[:, :3, 3] = out[:, :3, 3] - origin  # in float64, before the cast
        if not direct:
            for batch in world.query(WorldMatrix, with_=(Parent,)):
                first = plan.offsets[batch.table.id]
                batch[WorldMatrix].matrix = out[first : first + len(batch)]
            for batch in world.query(ModelMatrix, with_=(Parent,)):  # what is drawn
                first = plan.offsets[batch.table.id]
                batch[ModelMatrix].model = model[first : first + len(batch)]

    def _run_native(self, world: World, plan: _Plan, above: tuple[np.ndarray, ...], origin: np.ndarray) -> None:
        """The compiled pass: the first (largest) table's rows read and written in its own
        columns, the other tables' gathered into arrays kept between frames and copied back (a
        skinned crowd: 240k joints in place, 10k mesh nodes gathered); a level's rows are
        independent, cut into jobs on the pool."""
        tables, n = plan.tables, plan.count
        first = tables[0]
        split = first.count if first.has(Transform) else 0
        drawn_a = first.has(ModelMatrix)
        out_a, model_a = np.empty((0, 4, 4)), np.empty((0, 4, 4), np.float32)  # (none in place: unused)
        for batch in world.query(WorldMatrix, with_=(Parent,)):
            if split and batch.table is first:
                out_a = batch[WorldMatrix].matrix
        for batch in world.query(ModelMatrix, with_=(Parent,)):
            if split and batch.table is first:
                model_a = batch[ModelMatrix].model
        c = first.columns
        none = np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 3))
        trs_a = tuple(c[(Transform, f)][:split] for f in ("position", "rotation", "scale")) if split else none
        trs_b = self._local(plan, split)
        out_b, model_b = self._scratch(n - split)
        pool = world.resources.get(JobPool)

        def compose(rows: np.ndarray) -> None:
            _compose(  # type: ignore[misc]
                rows, plan.parent_row, plan.above_row, trs_a, trs_b, split, above,
                out_a, model_a, out_b, model_b, origin, drawn_a,
            )  # fmt: skip

        threads = 1 if pool is None else pool.threads
        if len(plan.levels[0]) >= TREES_PER_JOB * threads:  # whole trees a job: one call each, no level waits
            order, cuts = _tree_jobs(plan, 2 * threads if threads > 1 else 1)
            pieces = [order[a:b] for a, b in pairwise(cuts) if b > a]
            if pool is None or len(pieces) == 1:
                for piece in pieces:
                    compose(piece)
            else:
                pool.map(compose, pieces)
        else:
            for rows in plan.levels:

                def chunk(s: slice, rows: np.ndarray = rows) -> None:
                    compose(rows[s])

                over_rows(pool, len(rows), chunk, chunk_rows=LEVEL_CHUNK_ROWS)
        for batch in world.query(WorldMatrix, with_=(Parent,)):
            if batch.table is not first or not split:
                at = plan.offsets[batch.table.id] - split
                batch[WorldMatrix].matrix = out_b[at : at + len(batch)]
        for batch in world.query(ModelMatrix, with_=(Parent,)):  # what is drawn
            if batch.table is not first or not split:
                at = plan.offsets[batch.table.id] - split
                batch[ModelMatrix].model = model_b[at : at + len(batch)]

    def _scratch(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The pass's output arrays for `n` rows when they are copied out per table: kept between
        frames (fresh ones would fault their pages in every frame: ~5 ms at 250k rows)."""
        if self._out is None or len(self._out[0]) != n:
            self._out = (np.empty((n, 4, 4)), np.empty((n, 4, 4), np.float32))
        return self._out

    def _local(self, plan: _Plan, skip: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The position, rotation and scale of the rows from `skip` on: the table's columns
        themselves when there is one table with Transform, else gathered (identity where a table
        has no Transform) into arrays kept between frames."""
        tables, n = [t for t in plan.tables if plan.offsets[t.id] >= skip], plan.count - skip
        if len(tables) == 1 and tables[0].has(Transform):
            c = tables[0].columns
            return c[(Transform, "position")][:n], c[(Transform, "rotation")][:n], c[(Transform, "scale")][:n]
        if self._gathered is None or len(self._gathered[0]) != n:  # (n 0: empty, nothing to gather)
            self._gathered = (np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 3)))
        position, rotation, scale = self._gathered
        if not all(t.has(Transform) for t in tables):
            position[:], rotation[:], scale[:] = 0.0, (0.0, 0.0, 0.0, 1.0), 1.0
        for t in tables:
            if t.has(Transform):
                rows = slice(plan.offsets[t.id] - skip, plan.offsets[t.id] - skip + t.count)
                for field, into in (("position", position), ("rotation", rotation), ("scale", scale)):
                    into[rows] = t.columns[(Transform, field)][: t.count]
        return position, rotation, scale

    @staticmethod
    def _above(plan: _Plan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, rotation and scale of the parents outside the hierarchy, as plan.above_row
        indexes them: the columns of their table when there is one, else gathered."""
        with_rows = [(table, rows) for table, rows, _ in plan.outside if len(rows)]
        if len(with_rows) == 1:
            table = with_rows[0][0]
            n = table.count
            c = table.columns
            return c[(Transform, "position")][:n], c[(Transform, "rotation")][:n], c[(Transform, "scale")][:n]
        if not with_rows:
            return np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]), np.ones((1, 3))

        def gathered(field: str) -> np.ndarray:
            return np.concatenate([t.columns[(Transform, field)][rows] for t, rows in with_rows])

        return gathered("position"), gathered("rotation"), gathered("scale")

    @staticmethod
    def _compose_numpy(
        plan: _Plan, trs: tuple[np.ndarray, ...], above: tuple[np.ndarray, ...], out: np.ndarray
    ) -> None:
        """The pass without numba: a batched matmul per level."""
        local = trs_matrices(*trs)
        above_world = np.broadcast_to(np.eye(4), (plan.count, 4, 4)).copy()
        mask = plan.above_row >= 0
        above_world[mask] = trs_matrices(*(a[plan.above_row[mask]] for a in above))
        for rows in plan.levels:
            parent = plan.parent_row[rows]
            inner = (parent >= 0)[:, None, None]
            out[rows] = np.where(inner, out[np.maximum(parent, 0)], above_world[rows]) @ local[rows]
