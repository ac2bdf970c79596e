"""Transform columns -> camera-relative float32 model matrices (ModelMatrix), and normal
matrices for entities that opt in with NormalMatrix."""

from __future__ import annotations

from typing import Any

import numpy as np

from ecs_engine.components import (
    ActiveCamera,
    Camera,
    ModelMatrix,
    NormalMatrix,
    PreviousTransform,
    RenderOrigin,
    RenderTexture,
    Transform,
    Viewport,
    active_camera,
    render_origin,
)
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.ecs.timestep import Interpolation
from ecs_engine.ecs.world import World
from ecs_engine.errors import UsageError
from ecs_engine.jobs import JobPool, over_rows
from ecs_engine.maths.transform import compose


class TransformSystem(System):
    """Rebuilds ModelMatrix only in tables whose Transform changed since its last run, unless
    the render origin moved (then every table). Large tables are split across the world's
    JobPool resource, if it has one.

    With fixed-step simulation (an Interpolation resource, see ecs_engine.ecs.timestep), entities
    that also have PreviousTransform are drawn between their last two steps, every frame:
    position interpolated linearly, rotation by normalised lerp."""

    def __init__(self) -> None:
        super().__init__(reads=[Transform, PreviousTransform], writes=[ModelMatrix, NormalMatrix], name="transform")
        self._origin: bytes | None = None  # the origin of the last run, as bytes
        self.rows_updated = 0
        # which of the four table kinds the world has (answers kept while its structure stays)
        self._normals = any_with(Transform, ModelMatrix, NormalMatrix)
        self._previous = any_with(Transform, ModelMatrix, PreviousTransform)

    def run(self, world: World, dt: float) -> None:
        origin = render_origin(world)
        key = origin.tobytes()
        moved = key != self._origin
        self._origin = key
        interpolation = world.resources.get(Interpolation)
        interpolated = (PreviousTransform,) if interpolation is not None else ()
        pool = world.resources.get(JobPool)
        updated = 0
        interpolate = interpolation is not None and self._previous(world)
        for with_normal in (False, True) if self._normals(world) else (False,):
            query = _matrix_query(world, with_normal, (), interpolated)
            for batch in query.iter() if moved else query.iter(changed=(Transform,)):
                t = batch[Transform]
                model = batch[ModelMatrix].model
                normal = batch[NormalMatrix].normal if with_normal else None

                def rows(s: slice, t: Any = t, m: np.ndarray = model, n: np.ndarray | None = normal) -> None:
                    compose(t.position[s], t.rotation[s], t.scale[s], origin, m[s], None if n is None else n[s])

                over_rows(pool, len(batch), rows)
                updated += len(batch)
            if interpolate:
                assert interpolation is not None
                alpha = float(interpolation.alpha)
                for batch in _matrix_query(world, with_normal, (PreviousTransform,), ()):
                    t, prev = batch[Transform], batch[PreviousTransform]
                    position = prev.position + (t.position - prev.position) * alpha
                    compose(
                        position,
                        nlerp(prev.rotation, t.rotation, alpha),
                        t.scale,
                        origin,
                        batch[ModelMatrix].model,
                        batch[NormalMatrix].normal if with_normal else None,
                    )
                    updated += len(batch)
        self.rows_updated = updated


def _matrix_query(world: World, with_normal: bool, extra: tuple[type, ...], without: tuple[type, ...]) -> Any:
    """Tables with Transform and ModelMatrix (and `extra`), with or without NormalMatrix."""
    if with_normal:
        return world.query(Transform, ModelMatrix, NormalMatrix, *extra, without=without)
    return world.query(Transform, ModelMatrix, *extra, without=(*without, NormalMatrix))


def nlerp(a: np.ndarray, b: np.ndarray, alpha: float) -> np.ndarray:
    """Normalised lerp of (n, 4) quaternions along the shorter arc."""
    sign = np.where(np.einsum("ij,ij->i", a, b) < 0.0, -1.0, 1.0)[:, None]
    q = a * (1.0 - alpha) + b * sign * alpha
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    return np.where(norm > 0, q / np.where(norm > 0, norm, 1.0), b)


class RenderOriginSystem(System):
    """Sets the RenderOrigin resource to the active camera's position, before the transform
    system runs, so this frame's matrices are relative to this frame's camera."""

    def __init__(self) -> None:
        # active_camera's reads: with several cameras it picks by tag, RenderTexture and Viewport order
        reads = [Camera, Transform, ActiveCamera, RenderTexture, Viewport]
        super().__init__(reads=reads, writes=[], name="render_origin")
        self._set: RenderOrigin | None = None
        self._stamp: tuple[int, ...] = ()

    def run(self, world: World, dt: float) -> None:
        current = world.resources.get(RenderOrigin)
        if current is not None and not current.follow_camera:
            return  # pinned
        try:
            eid = active_camera(world)
        except UsageError:
            if world.query(Camera, Transform, write=()).count() == 0:
                return  # nothing to follow (a scene without a camera renders nothing)
            raise
        stamp = world.change_stamp(eid, Transform)
        if current is not None and current is self._set and stamp == self._stamp:
            return  # the camera has not moved since this system set the origin
        position = world.get(eid, Transform).position
        self._set = world.resources[RenderOrigin] = RenderOrigin(position)
        self._stamp = stamp
