"""`--culling temporal`: frustum culling that re-tests a row only when its state could have
changed (seed 004's temporal coherence, conservative by construction; maths/coherence.py has
the bound and why).

Per table with a mesh the culler keeps, per row: visible or not, the time until which that
holds, and the sphere it was tested with. Each frame it re-tests
- every row of every table, when the frustum's shape (fov, aspect, near, far) or the speed
  limits changed, or the camera moved or turned faster than the times assumed: they assume a
  rung of the limits (_Assumed: a still camera's times are long) and never more than the limits
  (the camera's FlyCamera's, or the `SpeedLimits` resource), so a teleport re-tests all;
- every row of a table whose rows came or went (spawns, destroys, moves between tables);
- the rows whose time ran out: rows sit in buckets by expiry slot (1/120 s), so only the due
  buckets are read (the seed decremented only its queue's head);
- in a table whose rows' place in the world may have changed since the last frame (its
  Transform, PreviousTransform or WorldMatrix columns written; its ModelMatrix, without a
  Transform: not the ModelMatrix alone, which follows the render origin), the rows whose sphere
  moved further than their own speed bound allows since their test (from Velocity and
  AngularVelocity; none: any move), or changed size: a `world.set`, a teleport, a wrap-around.
The result per row equals exact per-frame culling, by the bound (tests and `bench culling` check
it against the exact test: no row missing); rows are never drawn that exact culling would cull,
except where `min_interval` holds a row visible for longer to save re-tests.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...components import AngularVelocity, Mesh, ModelMatrix, PreviousTransform, Transform, Velocity, WorldMatrix
from ...ecs.world import World
from ...maths.coherence import coherence
from ...maths.culling import bounding_spheres
from . import temporal_kernels as kernels

SLOT_S = 1.0 / 120.0  # expiry buckets' width
HORIZON_S = 4.0  # a row is re-tested at least this often
SLACK = 1e-6  # relative: float32 model matrices and the kernel's own rounding
_MODEL = (ModelMatrix, "model")


@dataclass(frozen=True)
class SpeedLimits:
    """World resource: how fast the camera may move (units/s) and turn (rad/s). Without it the
    active camera's FlyCamera gives them (move_speed, and turn_speed on both axes at once)."""

    move: float
    turn: float

    def __post_init__(self) -> None:
        for name in ("move", "turn"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"SpeedLimits.{name} must be finite and >= 0, got {value!r}")


DEFAULT_LIMITS = SpeedLimits(move=10.0, turn=math.pi)  # no controller: a camera moved by code


def speed_limits(world: World, camera: int) -> SpeedLimits:
    found = world.resources.get(SpeedLimits)
    if found is not None:
        return found
    from ...components.camera_control import FlyCamera

    if world.has(camera, FlyCamera):
        fly = world.get(camera, FlyCamera)
        return SpeedLimits(float(fly.move_speed), math.sqrt(2.0) * float(fly.turn_speed))
    return DEFAULT_LIMITS


@dataclass
class _Rows:
    """One table's rows as last tested."""

    version: int
    tick: tuple[int, ...]  # geometry_tick when last checked
    visible: np.ndarray  # bool (n,)
    slot: np.ndarray  # int64 (n,): the expiry bucket each row sits in
    center: np.ndarray  # (n, 3) the spheres tested, in the world (the render origin moves)
    radius: np.ndarray
    speed: np.ndarray  # (n,) the centres' own speed bound
    tested: np.ndarray  # (n,) when
    buckets: dict[int, list[np.ndarray]] = field(default_factory=dict)


@dataclass
class _Camera:
    eye: np.ndarray  # world, float64
    rotation: np.ndarray  # (3, 3)
    lens: np.ndarray
    origin: np.ndarray
    limits: SpeedLimits


@dataclass
class CullStats:
    tested: int = 0  # rows tested this frame
    everything: bool = False  # every row was (a frame that invalidated all)


RUNGS = (1 / 64, 1 / 16, 1 / 4, 1.0)  # fractions of the limits the rows' times may assume
CALM_FRAMES = 30  # frames the camera stays well under a lower rung before the times assume it


class _Assumed:
    """The speeds the rows' times assume, per axis (move, turn) a rung of RUNGS times the limit.
    A camera that goes faster than its rung raises it and every row is tested again (its time
    assumed less); one that stayed at most half the next rung down for CALM_FRAMES frames lowers
    it, with no test: the old times, made for faster, hold all the more. So a still or slow
    camera gets long times, and the limits are only what a time may ever assume: beyond them
    (a teleport) every row is tested again."""

    def __init__(self) -> None:
        self.rung = [len(RUNGS) - 1, len(RUNGS) - 1]
        self.recent: deque[tuple[float, float]] = deque(maxlen=CALM_FRAMES)

    def speeds(self, limits: SpeedLimits) -> SpeedLimits:
        return SpeedLimits(limits.move * RUNGS[self.rung[0]], limits.turn * RUNGS[self.rung[1]])

    def update(self, limits: SpeedLimits, move: float, turn: float) -> bool:
        """Take this frame's speeds; False when they exceeded what the times assumed."""
        self.recent.append((move, turn))
        valid = True
        for axis, (actual, limit) in enumerate(((move, limits.move), (turn, limits.turn))):
            need = next((k for k, f in enumerate(RUNGS) if actual <= f * limit), None)
            if need is None or need > self.rung[axis]:
                valid = False
                self.rung[axis] = len(RUNGS) - 1 if need is None else need
                self.recent.clear()
            elif self.rung[axis] > 0 and len(self.recent) == CALM_FRAMES:
                lower = RUNGS[self.rung[axis] - 1] * limit
                if max(r[axis] for r in self.recent) <= 0.5 * lower:
                    self.rung[axis] -= 1
        return valid


class TemporalCuller:
    def __init__(self, min_interval: float = 0.0) -> None:
        self.min_interval = float(min_interval)  # seconds a visible row is held at least
        self.now = 0.0
        self._rows: dict[int, _Rows] = {}
        self._camera: _Camera | None = None
        self._world: Any = None
        self.stats = CullStats()
        self.assumed = _Assumed()

    def reset(self) -> None:
        self._rows.clear()
        self._camera = None

    def masks(
        self, world: World, cam: Any, origin: np.ndarray, planes: np.ndarray, dt: float | None, bounds: Any
    ) -> dict[int, np.ndarray]:
        """Per table id with a Mesh and a ModelMatrix: the rows to draw (bool). `cam`: this
        frame's CameraMatrices; `planes`: its frustum (render-relative); `dt`: seconds since
        the last frame (None: unknown, so any camera move re-tests all); `bounds`: the mesh
        registry's (centres, radii, index counts)."""
        if world is not self._world:
            self.reset()
            self._world = world
        step = 0.0 if dt is None else max(float(dt), 0.0)
        self.now += step
        camera = _Camera(
            np.asarray(cam.position, np.float64),
            np.asarray(cam.inverse_view, np.float64)[:3, :3],
            np.asarray(cam.lens, np.float64),
            np.asarray(origin, np.float64),
            speed_limits(world, cam.entity),
        )
        if not self._still_valid(camera, dt):
            self._rows.clear()
        self._camera = camera
        self.stats = CullStats(everything=not self._rows)
        assumed = self.assumed.speeds(camera.limits)
        eye = camera.eye - camera.origin  # render-relative, as the planes and model matrices are
        offsets = np.abs(planes[:, :3] @ eye + planes[:, 3])
        out = {}
        seen = set()
        for batch in world.query(ModelMatrix, Mesh, write=()):
            table = batch.table
            seen.add(table.id)
            state = self._rows.get(table.id)
            tick = geometry_tick(table)
            if state is None or state.version != table.version:
                state = self._rows[table.id] = self._test_all(batch, planes, eye, offsets, assumed, bounds, tick)
            else:
                due = self._due(state)
                if tick != state.tick:
                    due = np.union1d(due, self._moved(batch, state, bounds))
                    state.tick = tick
                if len(due):
                    self._test(batch, state, due, planes, eye, offsets, assumed, bounds)
            out[table.id] = state.visible
        for gone in set(self._rows) - seen:
            del self._rows[gone]
        return out

    # ------------------------------------------------------------------ invalidation
    def _still_valid(self, camera: _Camera, dt: float | None) -> bool:
        """Whether the rows' times still hold: the same frustum shape and limits, and the camera
        moved and turned no faster than the speeds the times assumed (which this updates)."""
        last = self._camera
        if last is None or last.limits != camera.limits or not np.array_equal(last.lens, camera.lens):
            self.assumed = _Assumed()
            return False
        moved = float(np.linalg.norm(camera.eye - last.eye))
        turned = _angle(last.rotation, camera.rotation)
        if dt is None or dt <= 0.0:
            return moved == 0.0 and turned == 0.0
        moved = max(moved - SLACK * (1.0 + float(np.abs(camera.eye).max())), 0.0)
        turned = max(turned - 1e-9, 0.0)
        return self.assumed.update(camera.limits, moved / dt, turned / dt)

    # ------------------------------------------------------------------------ tests
    def _test_all(
        self,
        batch: Any,
        planes: np.ndarray,
        eye: np.ndarray,
        offsets: np.ndarray,
        limits: SpeedLimits,
        bounds: Any,
        tick: tuple[int, ...],
    ) -> _Rows:
        n = len(batch)
        state = _Rows(
            batch.table.version,
            tick,
            np.zeros(n, np.bool_),
            np.zeros(n, np.int64),
            np.zeros((n, 3)),
            np.zeros(n),
            np.zeros(n),
            np.zeros(n),
        )
        self._test(batch, state, np.arange(n), planes, eye, offsets, limits, bounds)
        return state

    def _test(
        self,
        batch: Any,
        state: _Rows,
        rows: np.ndarray,
        planes: np.ndarray,
        eye: np.ndarray,
        offsets: np.ndarray,
        limits: SpeedLimits,
        bounds: Any,
    ) -> None:
        self.stats.tested += len(rows)
        retest = _retest_compiled if kernels.retest_native is not None else _retest_numpy
        c, r, speed, visible, keep = retest(batch, rows, planes, eye, offsets, limits, bounds)
        if self.min_interval > 0.0:  # held visible: an extra draw instead of a re-test soon
            held = keep < self.min_interval
            visible = visible | held
            keep = np.where(held, self.min_interval, keep)
        state.visible[rows] = visible
        origin = self._camera.origin if self._camera is not None else np.zeros(3)
        state.center[rows], state.radius[rows], state.speed[rows] = c + origin, r, speed
        state.tested[rows] = self.now
        expiry = self.now + np.minimum(keep, HORIZON_S)
        # the bucket that ends before the expiry; rows due now go to the next frame's
        slot = np.maximum(np.floor(expiry / SLOT_S).astype(np.int64), int(self.now // SLOT_S) + 1)
        state.slot[rows] = slot
        order = np.argsort(slot, kind="stable")
        cuts = np.flatnonzero(np.diff(slot[order])) + 1
        for part in np.split(rows[order], cuts):
            state.buckets.setdefault(int(state.slot[part[0]]), []).append(part)

    def _due(self, state: _Rows) -> np.ndarray:
        """Rows whose bucket's time has come (a row re-bucketed since sits later: skipped)."""
        now_slot = int(self.now // SLOT_S)
        parts = []
        for slot in sorted(k for k in state.buckets if k <= now_slot):
            for rows in state.buckets.pop(slot):
                parts.append(rows[state.slot[rows] == slot])
        return np.unique(np.concatenate(parts)) if parts else np.empty(0, np.int64)

    def _moved(self, batch: Any, state: _Rows, bounds: Any) -> np.ndarray:
        """Rows whose sphere moved beyond its own speed bound since its test, or changed size."""
        centers, radii, _ = bounds
        model = batch[ModelMatrix].model[: len(state.visible)]
        handle = batch[Mesh].handle[: len(state.visible)]
        origin = self._camera.origin if self._camera is not None else np.zeros(3)
        if kernels.moved_native is not None:
            out = np.zeros(len(handle), np.bool_)
            last = (state.center, state.radius, state.speed, state.tested)
            kernels.moved_native(model, handle, centers, radii, origin, *last, self.now, SLACK, out)
            return np.flatnonzero(out)
        c, r = bounding_spheres(model, centers[handle], radii[handle])
        allowed = state.speed * (self.now - state.tested) + SLACK * (1.0 + np.abs(c).max(axis=1))
        moved = np.linalg.norm(c + origin - state.center, axis=1) > allowed
        resized = np.abs(r - state.radius) > SLACK * (1.0 + r)
        return np.flatnonzero(moved | resized)


_GEOMETRY = (Transform, PreviousTransform, WorldMatrix)


def geometry_tick(table: Any) -> tuple[int, ...]:
    """The write ticks of what places a table's rows in the world. With a Transform, the
    ModelMatrix is TransformSystem's (or HierarchySystem's, from WorldMatrix) function of them and
    of the render origin, which moves with the camera every frame: a still table whose matrices
    were only made relative to a new origin keeps its tick."""
    if not table.has(Transform):
        return (table.column_ticks[_MODEL],)
    return tuple(tick for (ct, _), tick in table.column_ticks.items() if ct in _GEOMETRY)


def _retest_compiled(
    batch: Any,
    rows: np.ndarray,
    planes: np.ndarray,
    eye: np.ndarray,
    offsets: np.ndarray,
    limits: SpeedLimits,
    bounds: Any,
) -> tuple[np.ndarray, ...]:
    """_retest_numpy's results from temporal_kernels.py's loop."""
    table, none = batch.table, np.zeros((0, 3))
    linear = table.columns[(Velocity, "linear")] if table.has(Velocity) else none
    angular = table.columns[(AngularVelocity, "angular")] if table.has(AngularVelocity) else none
    out = np.empty((len(rows), 7))
    model, handle = batch[ModelMatrix].model, batch[Mesh].handle
    args = (planes, offsets, eye, limits.move, limits.turn, linear, angular, SLACK, out)
    kernels.retest_native(rows, model, handle, bounds[0], bounds[1], *args)  # type: ignore[misc]
    return out[:, :3], out[:, 3], out[:, 4], out[:, 5] > 0.5, out[:, 6]


def _retest_numpy(
    batch: Any,
    rows: np.ndarray,
    planes: np.ndarray,
    eye: np.ndarray,
    offsets: np.ndarray,
    limits: SpeedLimits,
    bounds: Any,
) -> tuple[np.ndarray, ...]:
    """The rows' spheres, own speed bounds, state and seconds kept (temporal_kernels.py's test)."""
    centers, radii, _ = bounds
    model = batch[ModelMatrix].model[rows]
    handle = batch[Mesh].handle[rows]
    c, r = bounding_spheres(model, centers[handle], radii[handle])
    r_test = r * (1.0 + SLACK) + SLACK * (1.0 + np.abs(c).max(axis=1, initial=0.0))  # never cull what exact keeps
    speed = _own_speed(batch, rows, c - model[:, :3, 3])
    distances = c @ planes[:, :3].T + planes[:, 3]
    far = np.linalg.norm(c - eye, axis=1)
    visible, keep = coherence(distances, r_test, far, offsets, limits.move, limits.turn, speed)
    return c, r, speed, visible, keep


def _own_speed(batch: Any, rows: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Each sphere centre's speed bound: |Velocity| plus |AngularVelocity| times the centre's
    distance from the pivot; 0 without them (the verification catches any other move)."""
    speed = np.zeros(len(rows))
    table = batch.table
    if table.has(Velocity):
        speed += np.linalg.norm(table.columns[(Velocity, "linear")][rows], axis=1)
    if table.has(AngularVelocity):
        speed += np.linalg.norm(table.columns[(AngularVelocity, "angular")][rows], axis=1) * np.linalg.norm(
            offset, axis=1
        )
    return speed


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle of the rotation taking orientation a to b (3x3 each)."""
    cos = (np.trace(a.T @ b) - 1.0) / 2.0
    return float(np.arccos(np.clip(cos, -1.0, 1.0)))
